"""From noise-free simulated observations the fit recovers the truth to 1e-6 km (and 1e-9 km/s):
CR3BP with the ``ground-telescope`` (az/el), ephemeris dynamics with the ``real-telescope``
(astrometric RA/Dec), and with the epoch in the middle of the arc."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares import fit_orbit
from cistrack.units import LU_KM, VU_KMS

from .arcs import GUESS_OFFSET, cr3bp_arc, ephemeris_arc


def _errors_km(res, truth):
    e = res.state - truth
    return np.abs(e[:3]).max() * LU_KM, np.abs(e[3:]).max() * VU_KMS


def test_recovers_the_truth_to_1e_6_km_in_cr3bp_from_noise_free_az_el():
    arc = cr3bp_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.exact, arc.truth0 + GUESS_OFFSET, 0.0)
    pos, vel = _errors_km(res, arc.truth0)
    assert res.converged and res.n_rejected == 0
    assert pos < 1e-6 and vel < 1e-9, (pos, vel)


def test_recovers_the_truth_to_1e_6_km_in_ephemeris_dynamics_from_noise_free_ra_dec():
    arc = ephemeris_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.exact, arc.truth0 + GUESS_OFFSET, 0.0)
    pos, vel = _errors_km(res, arc.truth0)
    assert res.converged and res.n_rejected == 0
    assert pos < 1e-6 and vel < 1e-9, (pos, vel)


def test_epoch_inside_the_arc_propagates_both_ways_and_recovers_the_truth_there():
    arc = cr3bp_arc()
    k = len(arc.times) // 2
    t_mid = float(arc.times[k])
    res = fit_orbit(arc.dynamics, arc.sensor, arc.exact, arc.truth[k] + GUESS_OFFSET, t_mid)
    pos, vel = _errors_km(res, arc.truth[k])
    assert res.converged and res.epoch == t_mid
    assert pos < 1e-3 and vel < 1e-8, (pos, vel)   # data and fit propagate from different epochs
