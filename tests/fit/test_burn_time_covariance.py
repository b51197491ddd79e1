"""A fit with a burn holds the burn's time fixed; its state covariance takes the time's uncertainty
(cistrack.fitting.maneuver_search._with_burn_times), d d^T sigma_t^2 with d = d x(epoch) / d t_b.
Checked against the central difference of two trajectories with the burn 0.0001 TU either side,
integrated by scipy's plain CR3BP (tests/reference_cr3bp.py), not cistrack's dynamics: in the
rotating frame a later burn changes the velocity too (the Coriolis term of the delta-v), which a
first version, moving the position only, had missed by a factor of 50."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from cistrack.fitting.maneuver_search import _with_burn_times
from cistrack.least_squares.impulse_fit import MS_PER_VU, BurnEstimate

from reference_cr3bp import cr3bp_rhs  # tests/ is on sys.path

X0 = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])  # a 9:2 NRHO-like state, LU and VU
T_B, EPOCH, DV_MS = 0.4, 1.0, np.array([0.3, -0.2, 0.1])


@dataclass(frozen=True)
class _Fit:
    state: np.ndarray
    epoch: float
    covariance: np.ndarray
    full_covariance: np.ndarray


def _flown(t_b: float) -> np.ndarray:
    """The state at EPOCH of X0 flown from 0 with the burn at ``t_b``."""
    kw = dict(rtol=1e-12, atol=1e-14, method="DOP853")
    pre = solve_ivp(cr3bp_rhs, (0.0, t_b), X0, **kw).y[:, -1]
    pre[3:] += DV_MS / MS_PER_VU
    return solve_ivp(cr3bp_rhs, (t_b, EPOCH), pre, **kw).y[:, -1]


def test_the_state_covariance_takes_the_burn_times_term(registry):
    dynamics = registry.create("dynamics", "cr3bp")
    state = _flown(T_B)
    sigma_t, h = 0.02, 1e-4
    fit = _Fit(state, EPOCH, np.eye(6) * 1e-12, np.eye(9) * 1e-12)
    burn = BurnEstimate(T_B, DV_MS, np.eye(3) * 1e-4, sigma_t, np.zeros(3))
    out = _with_burn_times(fit, dynamics, dynamics, [burn])
    d = (_flown(T_B + h) - _flown(T_B - h)) / (2 * h)          # d x(epoch) / d t_b
    np.testing.assert_allclose(out.covariance - fit.covariance, np.outer(d, d) * sigma_t ** 2,
                               rtol=2e-2, atol=1e-3 * sigma_t ** 2 * float(d @ d))
    np.testing.assert_allclose(out.full_covariance[:6, :6], out.covariance)
    np.testing.assert_array_equal(out.full_covariance[6:, 6:], fit.full_covariance[6:, 6:])


def test_a_burn_without_a_measured_time_adds_nothing(registry):
    dynamics = registry.create("dynamics", "cr3bp")
    fit = _Fit(_flown(T_B), EPOCH, np.eye(6), np.eye(9))
    assert _with_burn_times(fit, dynamics, dynamics, [BurnEstimate(T_B, DV_MS, np.eye(3))]) is fit
