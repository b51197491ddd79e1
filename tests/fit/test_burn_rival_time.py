"""Another burn time the measurements allow as well as the estimate's, with a delta-v that the two
estimates' covariances together do not cover (cistrack.least_squares.burn_search.rival_time), on a linear problem: a
force-free particle whose position is measured, one observation at the prior's epoch (t = 0), an
uninformative pass at 2.0-2.2, two passes after a burn at 3.0."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .linear_components import FreeParticle, PositionSensor, burned_free_particle
from cistrack.least_squares import fit_orbit
from cistrack.least_squares.burn_search import ManeuverSearch, flown, rival_time
from cistrack.least_squares.impulse_fit import BurnArc, fit_impulses
from cistrack.model.measurement import MeasurementSet

X0 = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])
DV = np.array([0.0, 0.002, -0.001])  # VU, about 2 m/s
TB = 3.0
TIMES = np.array([0.0, 2.0, 2.1, 2.2, 4.0, 4.1, 4.2, 6.0, 6.1, 6.2])


def _truth(t):
    return burned_free_particle(X0, DV, TB, t)


def _judged(v_sigma, tb):
    """rival_time of a burn fitted at ``tb`` with its fixed-time covariance (t_sigma 0.1), the
    prior's velocity sigma ``v_sigma`` (VU); noise-free positions, pass 2.0-2.2 with sigma 1."""
    sen = PositionSensor()
    ms = sen.simulate(np.array([_truth(t) for t in TIMES]), TIMES, np.random.default_rng(1))
    sig = np.array(ms.sigmas, dtype=float)
    sig[1:4] = 1.0
    vals = np.array([_truth(t)[:3] for t in TIMES])
    ms = MeasurementSet(ms.times, vals, sig, ms.names, dict(ms.meta), ms.sites, ms.kinds, dict(ms.site_table))
    prior = (X0.copy(), np.diag([1e-12] * 3 + [v_sigma ** 2] * 3))
    dyn = FreeParticle()
    arc = BurnArc(dyn, sen, ms, None, prior)
    one = fit_impulses(arc, X0, 0.0, [tb])
    burn = replace(one.burns[0], t_sigma=0.1)
    found = ManeuverSearch(one.fit, flown(dyn, [burn]), [burn], [(0.0, 2.0) if tb < 2 else (2.2, 4.0)], [], prior)
    return burn, rival_time(arc, fit_orbit(dyn, sen, ms, X0, 0.0, prior=prior), found, burn, TIMES[-1])


def test_a_burn_time_the_measurements_do_not_place_has_a_rival_with_another_delta_v():
    """With a loose prior on the velocity a burn anywhere before the pass at 4.0 fits the noise-free
    data: the estimate at 1.0 has a rival, whose delta-v (near the truth's, at 3.0) lies far outside
    the two covariances."""
    burn, rival = _judged(1.0, 1.0)
    assert rival is not None and rival.cost_delta <= 4.0 and rival.chi2 > 1e3
    assert np.linalg.norm(rival.delta_v_ms - burn.delta_v_ms) > 1.0


def test_a_burn_time_the_prior_and_measurements_place_has_no_rival():
    """With the prior's velocity as sharp as the positions only the true time fits."""
    _, rival = _judged(1e-6, TB)
    assert rival is None
