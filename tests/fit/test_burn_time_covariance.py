"""A fit with a burn holds the burn's time fixed; its state covariance takes the time's uncertainty
(cistrack.fitting.maneuver_search._with_burn_times): the spread of the states of the arc refitted
with the burn at other times, over the time's Gaussian.

Checked on a linear problem with a closed-form answer to compare with: a force-free particle whose
position is measured at 0.0-0.2 and 2.0-2.2 (they fix the orbit before the burn) and once at 4.0,
after a burn near 3.0 (its three numbers fix the delta-v for a given burn time). Refitted with the
burn at t, the velocity at the epoch 4.0 is the pre-burn one plus DV (4 - 3) / (4 - t): not linear
in t. The reference is a 20-point Gauss-Hermite quadrature over t of refits, not the fit's own
three points. A derivative that holds the pre-burn orbit and delta-v fixed moves the epoch's
position instead (by -DV per unit of time), which the measurement at 4.0 does not allow: it had
left the truth at Mahalanobis^2 120 and 72 on unseen survey sets."""
from __future__ import annotations

import numpy as np

from .linear_components import FreeParticle, PositionSensor, burned_free_particle
from cistrack.fitting.maneuver_search import _with_burn_times
from cistrack.least_squares.impulse_fit import BurnArc, BurnEstimate, fit_impulses
from cistrack.model.measurement import MeasurementSet

X0 = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])
DV = np.array([0.0, 0.002, -0.001])  # VU
TB, EPOCH, GAP = 3.0, 4.0, (2.2, 4.0)
TIMES = np.array([0.0, 0.1, 0.2, 2.0, 2.1, 2.2, 4.0])


def _truth(t: float) -> np.ndarray:
    return burned_free_particle(X0, DV, TB, t)


def _arc() -> BurnArc:
    sen = PositionSensor()
    ms = sen.simulate(np.array([_truth(t) for t in TIMES]), TIMES, np.random.default_rng(1))
    noise_free = np.array([_truth(t)[:3] for t in TIMES])
    ms = MeasurementSet(ms.times, noise_free, ms.sigmas, ms.names, dict(ms.meta), ms.sites, ms.kinds,
                        dict(ms.site_table))
    return BurnArc(FreeParticle(), sen, ms)


def _state_with_burn_at(arc: BurnArc, t: float) -> np.ndarray:
    return fit_impulses(arc, _truth(EPOCH), EPOCH, [t]).fit.state


def _quadrature_spread(arc: BurnArc, sigma_t: float) -> np.ndarray:
    """E[(x(t) - x(TB))(x(t) - x(TB))^T] over t ~ N(TB, sigma_t^2), Gauss-Hermite, 20 points (all inside the gap)."""
    y, w = np.polynomial.hermite.hermgauss(20)
    x_tb = _state_with_burn_at(arc, TB)
    out = np.zeros((6, 6))
    for yk, wk in zip(y, w):
        d = _state_with_burn_at(arc, TB + np.sqrt(2.0) * sigma_t * yk) - x_tb
        out += wk / np.sqrt(np.pi) * np.outer(d, d)
    return out


def test_the_state_covariance_takes_the_spread_of_the_refits_over_the_burn_time():
    arc, sigma_t = _arc(), 0.1
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [TB])
    burn = BurnEstimate(TB, one.burns[0].delta_v_ms, one.burns[0].covariance_ms2, sigma_t, np.zeros(3))
    out = _with_burn_times(arc, one.fit, [burn], [GAP])
    added = np.asarray(out.covariance) - np.asarray(one.fit.covariance)
    reference = _quadrature_spread(arc, sigma_t)
    linear_only = np.outer(DV, DV) * sigma_t ** 2  # d v / d t_b = DV at TB
    np.testing.assert_allclose(added[3:, 3:], reference[3:, 3:], rtol=0.02, atol=1e-3 * reference[4, 4])
    assert abs(reference[4, 4] / linear_only[1, 1] - 1.0) > 0.05  # the curvature matters here
    np.testing.assert_allclose(added[:3, :3], 0.0, atol=1e-3 * reference[4, 4])  # measured at the epoch


def test_the_full_covariance_carries_the_same_state_block_and_keeps_the_rest():
    arc = _arc()
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [TB])
    burn = BurnEstimate(TB, one.burns[0].delta_v_ms, one.burns[0].covariance_ms2, 0.1, np.zeros(3))
    out = _with_burn_times(arc, one.fit, [burn], [GAP])
    np.testing.assert_allclose(np.asarray(out.full_covariance)[:6, :6], out.covariance)
    np.testing.assert_array_equal(np.asarray(out.full_covariance)[6:, 6:], np.asarray(one.fit.full_covariance)[6:, 6:])


def test_a_burn_time_point_beyond_its_gap_is_kept_inside_it():
    """A time sigma of 2 would put the later point past the observation at 4.0; kept at the gap's
    end, the refit's burn still lies before it."""
    arc = _arc()
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [TB])
    burn = BurnEstimate(TB, one.burns[0].delta_v_ms, one.burns[0].covariance_ms2, 2.0, np.zeros(3))
    out = _with_burn_times(arc, one.fit, [burn], [(2.2, 3.9)])
    d_lo = _state_with_burn_at(arc, 2.2) - one.fit.state
    d_hi = _state_with_burn_at(arc, 3.9) - one.fit.state
    expected = (np.outer(d_lo, d_lo) + np.outer(d_hi, d_hi)) / 6.0
    np.testing.assert_allclose(np.asarray(out.covariance) - one.fit.covariance, expected, rtol=1e-6,
                               atol=1e-9 * expected[4, 4])


def test_a_burn_without_a_measured_time_adds_nothing():
    arc = _arc()
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [TB])
    assert _with_burn_times(arc, one.fit, [BurnEstimate(TB, one.burns[0].delta_v_ms, np.eye(3))], [GAP]) is one.fit


def _epoch_velocity_shift(t: float, t_b: float) -> np.ndarray:
    """Closed form: refitted with the burn at ``t`` instead of ``t_b``, the state at EPOCH moves by
    DV (EPOCH - TB) (1 / (EPOCH - t) - 1 / (EPOCH - t_b)) in velocity and not in position (the
    pre-burn orbit is fixed by the first two passes, the delta-v by the position at EPOCH)."""
    d = np.zeros(6)
    d[3:] = DV * (EPOCH - TB) * (1.0 / (EPOCH - t) - 1.0 / (EPOCH - t_b))
    return d


def test_a_sigma_point_beyond_its_gap_is_stood_for_by_the_other():
    """A burn at 2.4 +- 0.3 in the gap 2.2-4.0: its earlier point (1.88) lies before the gap's start,
    so the later one (2.92) alone gives the spread, d d^T / 3 (the rule's (d+ d+^T + d- d-^T) / 6
    with d- = d+), not a point clipped to the gap's start."""
    arc, t_b, sigma_t = _arc(), 2.4, 0.3
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [t_b])
    burn = BurnEstimate(t_b, one.burns[0].delta_v_ms, one.burns[0].covariance_ms2, sigma_t, np.zeros(3))
    out = _with_burn_times(arc, one.fit, [burn], [GAP])
    d = _epoch_velocity_shift(t_b + np.sqrt(3.0) * sigma_t, t_b)
    np.testing.assert_allclose(np.asarray(out.covariance) - one.fit.covariance, np.outer(d, d) / 3.0,
                               rtol=1e-5, atol=1e-9 * d[4] ** 2)


def test_a_widened_burn_carries_the_orbit_of_the_time_that_widened_it():
    """A burn at 3.0 +- 0.1 widened to reach 3.8, 2 of its sigmas away: the state covariance takes
    d d^T / 4 of the orbit refitted with the burn at 3.8 on top of the sigma points' spread (between
    two minima of the cost the sigma points lie where the arc allows no burn)."""
    arc, sigma_t = _arc(), 0.1
    one = fit_impulses(arc, _truth(EPOCH), EPOCH, [TB])
    burn = BurnEstimate(TB, one.burns[0].delta_v_ms, one.burns[0].covariance_ms2, sigma_t, np.zeros(3),
                        widened=True, reach=(3.8, 2.0))
    out = _with_burn_times(arc, one.fit, [burn], [GAP])
    step = np.sqrt(3.0) * sigma_t
    points = [_epoch_velocity_shift(TB + s * step, TB) for s in (-1.0, 1.0)]
    far = _epoch_velocity_shift(3.8, TB)
    expected = sum(np.outer(p, p) for p in points) / 6.0 + np.outer(far, far) / 4.0
    np.testing.assert_allclose(np.asarray(out.covariance) - one.fit.covariance, expected, rtol=1e-5,
                               atol=1e-9 * far[4] ** 2)


def test_a_widened_burn_records_the_allowed_time_that_sets_its_sigma():
    """Allowed at 3.5 (2 sigmas away) and at 3.2 (3 away): 3.5 sets the time's sigma, 0.25."""
    from cistrack.least_squares.burn_search import _widened

    b = BurnEstimate(TB, np.array([0.3, 0.0, 0.0]), np.eye(3) * 1e-4, 0.01, np.zeros(3))
    out = _widened(b, [(3.5, np.array([0.4, 0.0, 0.0]), 2.0), (3.2, np.array([0.35, 0.0, 0.0]), 3.0)])
    assert out.t_sigma == 0.25 and out.reach == (3.5, 2.0)
