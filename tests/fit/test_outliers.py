"""Chi-square outlier rejection: displaced observations are flagged and the estimate stays within
its covariance; rejected observations are readmitted when their chi-square falls back below the
threshold; rejection can be switched off."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.outliers import rejection_threshold, update_rejections
from cistrack.model.measurement import MeasurementSet
from cistrack.units import ARCSEC_RAD

from .arcs import GUESS_OFFSET, cr3bp_arc, ephemeris_arc

MAHALANOBIS2_99 = 16.81
"""Chi-square with 6 degrees of freedom at 99 %."""


def _with_outliers(arc, seed: int) -> tuple[MeasurementSet, np.ndarray]:
    """Noisy observations with 5 % of them displaced by 10-100 arcsec in a random direction."""
    rng = np.random.default_rng(seed)
    ms = arc.noisy(seed)
    k = len(ms)
    bad = rng.choice(k, size=max(1, int(round(0.05 * k))), replace=False)
    values = ms.values.copy()
    size = rng.uniform(10.0, 100.0, bad.size) * ARCSEC_RAD
    angle = rng.uniform(0.0, 2 * np.pi, bad.size)
    values[bad, 0] += size * np.cos(angle) / np.cos(values[bad, 1])   # on the sky
    values[bad, 1] += size * np.sin(angle)
    flags = np.zeros(k, dtype=bool)
    flags[bad] = True
    return MeasurementSet(ms.times, values, ms.sigmas, ms.names), flags


@pytest.mark.parametrize("arc_of", [cr3bp_arc, ephemeris_arc], ids=["cr3bp-azel", "ephemeris-radec"])
def test_displaced_observations_are_rejected_and_the_estimate_stays_within_its_covariance(arc_of):
    arc = arc_of()
    ms, outliers = _with_outliers(arc, seed=11)
    res = fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0)
    rejected = res.residuals.rejected
    assert np.all(rejected[outliers]), np.nonzero(outliers & ~rejected)
    assert np.sum(rejected & ~outliers) <= 1
    assert res.converged
    assert res.mahalanobis2(arc.truth0) < MAHALANOBIS2_99


def test_a_rejected_observation_whose_chi2_falls_below_the_threshold_is_readmitted():
    thr = rejection_threshold(3.0, 2)
    chi2 = np.array([1.0, 2.0, 0.5, thr * 0.9, thr * 4.0, 1.5])
    was = np.array([False, False, False, True, False, False])
    new, used_thr = update_rejections(chi2, 2, was, robust=False)
    assert used_thr == pytest.approx(thr)
    assert list(new) == [False, False, False, False, True, False]


def test_threshold_is_the_three_sigma_chi2_quantile_of_two_components():
    assert rejection_threshold(3.0, 2) == pytest.approx(11.829, abs=1e-3)


def test_robust_threshold_grows_with_the_median_chi2_so_a_poor_orbit_keeps_its_data():
    chi2 = np.full(20, 100.0)
    chi2[0] = 1e5
    new, thr = update_rejections(chi2, 2, np.zeros(20, dtype=bool))
    assert thr > 100.0 and list(np.nonzero(new)[0]) == [0]


def test_rejection_switched_off_uses_every_observation():
    arc = cr3bp_arc()
    ms, _ = _with_outliers(arc, seed=11)
    res = fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0,
                    options=FitOptions(reject_outliers=False))
    assert res.n_rejected == 0 and res.n_used == len(ms)
    assert res.noise_scale > 3.0    # the outliers inflate the residuals


def test_good_observations_rejected_by_a_biased_first_pass_are_readmitted():
    arc = cr3bp_arc()
    ms = arc.noisy(4)
    values = ms.values.copy()
    gross = {10: 3000.0, 11: 2500.0, 30: -2000.0}          # arcsec in elevation
    for i, size in gross.items():
        values[i, 1] += size * ARCSEC_RAD
    ms = MeasurementSet(ms.times, values, ms.sigmas, ms.names)
    res = fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0,
                    options=FitOptions(robust_threshold=False))    # the first pass rejects good data too
    assert any("readmitted" in m for m in res.messages), res.messages
    assert sorted(np.nonzero(res.residuals.rejected)[0].tolist()) == sorted(gross)
    assert res.converged and res.mahalanobis2(arc.truth0) < MAHALANOBIS2_99
