"""The iterated posterior-linearisation update used by the UKF, against independent references:
the exact Kalman update (linear h), filterpy's own UKF update (one iteration) and a posterior
computed by quadrature on a grid (a bearing measured far more precisely than the prior)."""
from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

from cistrack.errors import ParameterError
from cistrack.plugins.filters.posterior_linearization import (posterior_linearization_update,
                                                              posterior_linearization_updates)
from cistrack.plugins.filters.ukf import UKFFilter


def _points(d: int, alpha: float = 1.0, kappa: float = 0.0) -> MerweScaledSigmaPoints:
    return MerweScaledSigmaPoints(d, alpha=alpha, beta=2.0, kappa=kappa)


@pytest.mark.parametrize("iterations", [1, 2, 10])
@pytest.mark.parametrize("alpha", [1e-3, 1.0])
def test_linear_measurement_gives_the_exact_kalman_update_at_any_iteration_count(iterations, alpha):
    rng = np.random.default_rng(3)
    a = rng.standard_normal((4, 4))
    P0 = a @ a.T + 0.1 * np.eye(4)
    x0 = rng.standard_normal(4)
    H = rng.standard_normal((2, 4))
    R = np.diag([0.05, 0.2])
    z = rng.standard_normal(2)
    S = H @ P0 @ H.T + R
    K = P0 @ H.T @ np.linalg.inv(S)
    res = posterior_linearization_update(_points(4, alpha), x0, P0, lambda X: X @ H.T - z, R,
                                         max_iterations=iterations, tolerance=1e-12)
    np.testing.assert_allclose(res.x, x0 + K @ (z - H @ x0), rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(res.P, P0 - K @ S @ K.T, rtol=1e-7, atol=1e-9)


def test_one_iteration_is_filterpys_unscented_update():
    def h(x):
        return np.array([np.hypot(x[0], x[1]), x[0] * x[2] + np.sin(x[1])])

    x0 = np.array([3.0, 1.0, 0.5])
    P0 = np.array([[0.4, 0.1, 0.0], [0.1, 0.3, 0.05], [0.0, 0.05, 0.2]])
    R = np.diag([0.01, 0.02])
    z = np.array([3.3, 2.4])
    ref = UnscentedKalmanFilter(dim_x=3, dim_z=2, dt=1.0, hx=h, fx=lambda x, dt: x, points=_points(3))
    ref.x, ref.P, ref.R = x0.copy(), P0.copy(), R
    ref.sigmas_f = ref.points_fn.sigma_points(x0, P0)
    ref.update(z)
    res = posterior_linearization_update(_points(3), x0, P0, lambda X: np.array([h(x) for x in X]) - z, R,
                                         max_iterations=1)
    np.testing.assert_allclose(res.x, ref.x, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.P, ref.P, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.S, ref.S, rtol=1e-10)
    assert res.iterations == 1


# A bearing atan2(c, a) to a target whose range a is uncertain by 30 %: the measurement pins the
# ratio c/a, i.e. a line through the origin, far more tightly than the prior (the situation of
# the NRHO's noisy-range IOD cloud seen by 1.5 arcsec angles).
X0 = np.array([10.0, 0.0])
P0_BEARING = np.diag([3.0 ** 2, 3.0 ** 2])
SIGMA = 1e-3
Z = 0.3


def _bearing_residual(X):
    return (np.arctan2(X[:, 1], X[:, 0]) - Z)[:, None]


def _grid_posterior():
    """Posterior mean (2,) and covariance (2, 2) by quadrature on a fine grid in (a, bearing)."""
    a = np.linspace(-5.0, 25.0, 3001)
    b = Z + np.linspace(-8 * SIGMA, 8 * SIGMA, 801)
    A, B = np.meshgrid(a, b, indexing="ij")
    C = A * np.tan(B)
    jac = np.abs(A) / np.cos(B) ** 2            # d(a, c) = |a| sec^2(b) d(a, b)
    logp = (-0.5 * ((A - X0[0]) ** 2 + (C - X0[1]) ** 2) / 9.0 - 0.5 * ((B - Z) / SIGMA) ** 2)
    w = np.exp(logp - logp.max()) * jac
    w /= w.sum()
    pts = np.stack([A.ravel(), C.ravel()], axis=1)
    m = w.ravel() @ pts
    d = pts - m
    return m, (d.T * w.ravel()) @ d


def _expected_nees(m, P, m_true, P_true):
    """E[(x - m)^T P^-1 (x - m)] under the true posterior: 2 for a matching 2-D Gaussian."""
    Pi = np.linalg.inv(P)
    e = m_true - m
    return float(np.trace(Pi @ P_true) + e @ Pi @ e)


def test_iterated_update_covers_the_true_posterior_of_a_precise_bearing():
    m_true, P_true = _grid_posterior()
    res = posterior_linearization_update(_points(2), X0, P0_BEARING, _bearing_residual,
                                         np.array([[SIGMA ** 2]]), max_iterations=20, tolerance=1e-6)
    assert _expected_nees(res.x, res.P, m_true, P_true) == pytest.approx(2.0, abs=0.5)
    e = res.x - m_true                          # a Gaussian misses the skew along the line a little
    assert e @ np.linalg.solve(P_true, e) < 0.5 ** 2


def test_one_shot_update_is_overconfident_on_a_precise_bearing():
    m_true, P_true = _grid_posterior()
    res = posterior_linearization_update(_points(2), X0, P0_BEARING, _bearing_residual,
                                         np.array([[SIGMA ** 2]]), max_iterations=1)
    assert _expected_nees(res.x, res.P, m_true, P_true) > 20.0


def test_iterations_stop_once_the_mean_settles():
    res = posterior_linearization_update(_points(2), X0, P0_BEARING, _bearing_residual,
                                         np.array([[SIGMA ** 2]]), max_iterations=50, tolerance=1e-3)
    assert 1 < res.iterations < 50
    assert res.step < 1e-3


def _three_bearing_priors():
    """The bearing prior, a tighter one (it settles in fewer iterations) and a shifted one."""
    xs = np.array([X0, [9.0, 2.0], [12.0, 3.0]])
    Ps = np.array([P0_BEARING, np.diag([0.05 ** 2, 0.05 ** 2]), [[4.0, 1.0], [1.0, 6.0]]])
    return xs, Ps


def test_gaussians_updated_together_come_out_as_each_alone():
    xs, Ps = _three_bearing_priors()
    R = np.array([[SIGMA ** 2]])
    together = posterior_linearization_updates(_points(2), xs, Ps, _bearing_residual, R,
                                               max_iterations=20, tolerance=1e-6)
    assert len({res.iterations for res in together}) > 1  # they stopped at different iterations
    for i, res in enumerate(together):
        alone = posterior_linearization_update(_points(2), xs[i], Ps[i], _bearing_residual, R,
                                               max_iterations=20, tolerance=1e-6)
        assert res.iterations == alone.iterations and res.step == alone.step
        for name in ("x", "P", "innovation", "S", "innovation_final", "S_final"):
            assert np.array_equal(getattr(res, name), getattr(alone, name)), name


def test_gaussians_updated_together_share_one_sensor_call_per_iteration():
    xs, Ps = _three_bearing_priors()
    calls = []

    def residual(X):
        calls.append(X.shape[0])
        return _bearing_residual(X)

    together = posterior_linearization_updates(_points(2), xs, Ps, residual, np.array([[SIGMA ** 2]]),
                                               max_iterations=20, tolerance=1e-6)
    assert len(calls) == max(res.iterations for res in together)
    assert calls[0] == 3 * 5 and calls[-1] < calls[0]  # 2d+1 points each; the settled ones drop out


@pytest.mark.parametrize("name, value", [("update_iterations", 0), ("update_tolerance", 0.0),
                                         ("kappa", -6.0), ("update_iterations", 2.5),
                                         ("update_iterations", 1_000_000)])
def test_ukf_rejects_bad_iteration_settings(name, value):
    with pytest.raises(ParameterError, match=name):
        UKFFilter(**{name: value})


def test_pgm_rejects_a_million_update_iterations():
    from cistrack.plugins.filters.pgm.filter import PGMFilter

    with pytest.raises(ParameterError, match=r"update_iterations.*<= 1000"):
        PGMFilter(update_iterations=1_000_000)
