"""A fit's covariance carried by the unscented transform: sigma points that reproduce the covariance,
exact on linear dynamics, and right (against a Monte Carlo of the nonlinear flow) through a close
perilune, where the linear covariance P(t) = Phi P Phi^T is far too thin."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError, StateError
from cistrack.least_squares import fit_orbit, predict
from cistrack.least_squares.prediction import predict_orbit
from cistrack.least_squares.unscented_prediction import sigma_points, unscented_covariances
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.orbit_catalog import ORBITS

from .linear_components import FreeParticle, LinearSensor, free_particle_stm

NRHO = ORBITS["nrho-9-2"]
CHI2_6_99 = 16.81


def _spd(seed: int) -> np.ndarray:
    a = np.random.default_rng(seed).standard_normal((6, 6))
    return a @ a.T + 0.1 * np.eye(6)


def _about(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    d = points - centre
    return d.T @ d / len(points)


def test_sigma_points_reproduce_the_covariance_about_the_state():
    x, p = np.arange(6.0), _spd(1)
    pts = sigma_points(x, p)
    assert pts.shape == (12, 6)
    np.testing.assert_allclose(pts.mean(axis=0), x, atol=1e-12)
    np.testing.assert_allclose(_about(pts, x), p, rtol=1e-12, atol=1e-12)


def test_sigma_points_of_a_singular_covariance_stay_on_its_support():
    v = np.random.default_rng(2).standard_normal((6, 3))
    p = v @ v.T  # rank 3: no Cholesky factor
    pts = sigma_points(np.zeros(6), p)
    np.testing.assert_allclose(_about(pts, np.zeros(6)), p, atol=1e-12)


@pytest.mark.parametrize("cov, match", [
    (np.triu(np.ones((6, 6))), "not symmetric"),
    (-np.eye(6), "not positive semi-definite"),
    (np.full((6, 6), np.nan), "finite"),
    (np.eye(5), r"\(6, 6\)"),
], ids=["asymmetric", "negative", "nan", "wrong shape"])
def test_a_bad_covariance_is_refused_with_the_reason(cov, match):
    with pytest.raises(StateError, match=match):
        sigma_points(np.zeros(6), cov)


def test_the_unscented_covariance_is_phi_p_phi_transpose_on_linear_dynamics():
    p = _spd(3)
    times = np.array([-2.0, 0.0, 0.5, 3.0])
    covs, ok = unscented_covariances(FreeParticle(), np.ones(6), p, 0.0, times)
    assert ok.all()
    for k, t in enumerate(times):
        phi = free_particle_stm(t)
        np.testing.assert_allclose(covs[k], phi @ p @ phi.T, rtol=1e-10, atol=1e-12)


def test_predict_defaults_to_the_unscented_covariance_and_keeps_the_linear_one_on_request():
    dyn, sen = FreeParticle(), LinearSensor()
    times = np.linspace(0.0, 2.0, 6)
    res = fit_orbit(dyn, sen, sen.simulate(np.zeros((6, 6)), times, np.random.default_rng(2)), np.zeros(6), 1.0)
    _, unscented = predict(res, dyn, np.array([-1.0, 5.0]))
    _, linear = predict(res, dyn, np.array([-1.0, 5.0]), covariance="linear")
    np.testing.assert_allclose(unscented, linear, rtol=1e-8, atol=1e-30)
    with pytest.raises(ConfigError, match="covariance='cubic': must be one of unscented, linear"):
        predict(res, dyn, [1.0], covariance="cubic")


def _perilune_time(dyn) -> float:
    ts = np.linspace(0.0, NRHO.period, 4001)[1:]
    path = dyn.propagate(NRHO.state[None], 0.0, ts).states[:, 0, :3]
    return float(ts[np.argmin(np.linalg.norm(path - [1.0 - dyn.mu, 0.0, 0.0], axis=1))])


def _share_outside_99(samples, centre, cov):
    d = samples - centre
    return float(np.mean(np.einsum("ni,ij,nj->n", d, np.linalg.inv(cov), d) > CHI2_6_99))


def test_through_a_close_perilune_the_unscented_covariance_holds_a_monte_carlo_where_the_linear_one_fails():
    # 9:2 NRHO from apolune with 1 km / 1 mm/s (a well-determined orbit) to its perilune 1,500 km
    # above the Moon: 3,000 orbits drawn from the covariance and propagated with the full dynamics
    dyn = CR3BP()
    tp = _perilune_time(dyn)
    p0 = np.diag([(1.0 / units.LU_KM) ** 2] * 3 + [(1e-6 / units.VU_KMS) ** 2] * 3)
    samples = np.random.default_rng(62).multivariate_normal(NRHO.state, p0, 3000)
    cloud = dyn.propagate(samples, 0.0, tp).states[0]
    states, stms = dyn.propagate_with_stm(NRHO.state, 0.0, np.array([tp]))
    linear = stms[0] @ p0 @ stms[0].T
    unscented, ok = unscented_covariances(dyn, NRHO.state, p0, 0.0, np.array([tp]))
    assert ok.all()
    assert _share_outside_99(cloud, states[0], linear) > 0.5          # 0.80 measured
    assert _share_outside_99(cloud, states[0], unscented[0]) < 0.04   # 0.024 measured (1 % if Gaussian)


def test_times_after_a_sigma_point_orbit_hits_the_moon_keep_the_linear_covariance():
    # a lunar orbit whose perilune passes 460 km above the surface at t = 0.042 TU; velocity spread
    # wide enough that the slowest sigma points hit the Moon there
    dyn = CR3BP()
    x = np.r_[1.0 - dyn.mu + 0.02, 0.0, 0.0, 0.0, 0.5, 0.0]
    assert dyn.propagate(x[None], 0.0, 0.1).alive[0]
    p = np.diag([1e-8] * 3 + [0.02 ** 2] * 3)

    class Fit:  # what predict_orbit reads of a FitResult
        state, covariance, epoch = x, p, 0.0

    pred = predict_orbit(Fit, dyn, np.array([0.01, 0.1]))
    assert list(pred.linear) == [False, True]
    linear = predict_orbit(Fit, dyn, np.array([0.01, 0.1]), covariance="linear")
    np.testing.assert_array_equal(pred.covariances[1], linear.covariances[1])


def test_a_covariance_that_gives_no_sigma_points_keeps_the_linear_prediction():
    class Fit:  # an indefinite covariance, as a forced export of a failed fit may hold
        state, covariance, epoch = NRHO.state, np.diag([1e-8, 1e-8, -1e-8, 1e-8, 1e-8, 1e-8]), 0.0

    pred = predict_orbit(Fit, CR3BP(), np.array([0.1, 0.2]))
    linear = predict_orbit(Fit, CR3BP(), np.array([0.1, 0.2]), covariance="linear")
    assert pred.linear.all()
    np.testing.assert_array_equal(pred.covariances, linear.covariances)
