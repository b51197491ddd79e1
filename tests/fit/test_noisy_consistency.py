"""Noisy observations: the truth lies inside the fit's covariance for fixed seeds, and the
post-fit residuals estimate the noise (noise scale, residual RMS)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.least_squares import fit_orbit
from cistrack.model.measurement import MeasurementSet

from .arcs import GUESS_OFFSET, cr3bp_arc, ephemeris_arc

MAHALANOBIS2_99 = 16.81
"""Chi-square with 6 degrees of freedom at 99 %."""
SEEDS = (1, 2, 3, 4, 5)


@pytest.mark.parametrize("seed", SEEDS)
def test_truth_lies_inside_the_covariance_in_cr3bp(seed):
    arc = cr3bp_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.noisy(seed), arc.truth0 + GUESS_OFFSET, 0.0)
    assert res.converged
    assert res.mahalanobis2(arc.truth0) < MAHALANOBIS2_99


@pytest.mark.parametrize("seed", SEEDS[:3])
def test_truth_lies_inside_the_covariance_in_ephemeris_dynamics(seed):
    arc = ephemeris_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.noisy(seed), arc.truth0 + GUESS_OFFSET, 0.0)
    assert res.converged
    assert res.mahalanobis2(arc.truth0) < MAHALANOBIS2_99


def test_mean_mahalanobis2_over_seeds_is_near_six():
    arc = cr3bp_arc()
    m2 = [fit_orbit(arc.dynamics, arc.sensor, arc.noisy(s), arc.truth0 + GUESS_OFFSET, 0.0).mahalanobis2(arc.truth0)
          for s in range(20, 40)]
    assert 3.0 < np.mean(m2) < 10.0, m2     # 20 draws of chi-square(6): mean 6 +- 0.8


def test_noise_scale_reveals_overstated_sigmas():
    arc = ephemeris_arc()
    ms = arc.noisy(7)
    stated = MeasurementSet(ms.times, ms.values, 3.0 * ms.sigmas, ms.names)
    res = fit_orbit(arc.dynamics, arc.sensor, stated, arc.truth0 + GUESS_OFFSET, 0.0)
    assert res.noise_scale == pytest.approx(1.0 / 3.0, rel=0.2)


def test_residual_rms_is_within_20_percent_of_the_true_noise():
    arc = ephemeris_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.noisy(8), arc.truth0 + GUESS_OFFSET, 0.0)
    np.testing.assert_allclose(res.residuals.rms(), 0.5, rtol=0.2)   # arcsec, RA cos(Dec) and Dec
