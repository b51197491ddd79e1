"""The PGM resamples more particles while its cloud is reacquiring: its predicted measurements
spread wider than a threshold in noise units (plugins/filters/pgm/reacquisition_particles.py).
The count grows and shrinks as the rule says and stays deterministic with the seed."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import ParticleCloud
from cistrack.model.measurement import Measurement
from cistrack.plugins.filters.pgm import PaperPGMFilter, PGMFilter
from cistrack.plugins.filters.pgm.reacquisition_particles import measurement_spread_sigma, particles_to_draw

from .linear_models import LinearDynamics, LinearSensor

SIGMA = 0.01  # measurement noise of the linear sensor (LU)


def test_the_spread_is_the_largest_residual_standard_deviation_in_noise_units():
    rng = np.random.default_rng(1)
    R = np.array([[4.0, 1.2], [1.2, 1.0]]) * 1e-4
    L = np.linalg.cholesky(R)
    u = rng.standard_normal((200000, 2)) * np.array([30.0, 5.0])  # whitened: sd 30 and 5
    res = u @ L.T + np.array([0.3, -0.1])  # a common offset (the measurement) does not count
    assert measurement_spread_sigma(res, R) == pytest.approx(30.0, rel=0.01)


def test_a_single_residual_has_no_spread():
    assert measurement_spread_sigma(np.ones((1, 2)), np.eye(2)) == 0.0


@pytest.mark.parametrize("spread, factor, expected", [
    (5000.0, 4.0, 40000),   # wider than the threshold: factor x n
    (1000.0, 4.0, 10000),   # at the threshold: n
    (10.0, 4.0, 10000),     # narrow: n
    (5000.0, 1.0, 10000),   # factor 1: off
    (5000.0, 0.5, 10000),   # never fewer than n
])
def test_particles_to_draw_follows_the_threshold_rule(spread, factor, expected):
    assert particles_to_draw(spread, 10000, factor, 1000.0) == expected


def cloud(sd: float, n: int = 2000, seed: int = 0) -> ParticleCloud:
    """Positions with sd ``sd`` (LU), velocities nearly known (sd 1e-4 LU/TU)."""
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((n, 6)) * np.array([sd] * 3 + [1e-4] * 3)
    return ParticleCloud(x, 0.0)


def run_updates(filt, sds=(5.0,), seed=3):
    """Initialise with a cloud of position sd ``sds[0]`` (LU) and update at t = 0 and 1;
    returns the particle counts after each update."""
    rng = np.random.default_rng(seed)
    sensor = LinearSensor(sigma=SIGMA)
    filt.initialize(cloud(sds[0]), LinearDynamics(), sensor, rng)
    counts = []
    for t in (0.0, 1.0):
        filt.predict(t)
        filt.update(Measurement(t, np.array([0.01, -0.02]), SIGMA**2 * np.eye(2), sensor.names))
        counts.append(filt.belief.samples.states.shape[0])
    return counts


def test_a_wide_cloud_is_resampled_with_more_particles_and_the_count_shrinks_once_it_is_narrow():
    # first prior: 5 LU / 0.01 LU = 500 noise sigmas > 100, so 3 x 2000 particles; the posterior
    # is about one noise sigma wide and the velocities barely spread it over 1 TU, so the second
    # prior is narrow and the count returns to 2000
    filt = PGMFilter(n_particles=2000, n_components=2, reacquire_factor=3.0, reacquire_spread_sigma=100.0)
    assert run_updates(filt) == [6000, 2000]
    assert filt.diagnostics["prior_spread_sigma"] < 10.0


def test_a_narrow_cloud_keeps_n_particles():
    filt = PGMFilter(n_particles=2000, n_components=2, reacquire_factor=3.0, reacquire_spread_sigma=1e4)
    assert run_updates(filt) == [2000, 2000]


def test_the_reacquisition_count_is_deterministic_with_the_seed():
    a = PGMFilter(n_particles=1000, n_components=2, reacquire_factor=2.0, reacquire_spread_sigma=100.0)
    b = PGMFilter(n_particles=1000, n_components=2, reacquire_factor=2.0, reacquire_spread_sigma=100.0)
    run_updates(a, seed=11)
    run_updates(b, seed=11)
    np.testing.assert_array_equal(a.belief.samples.states, b.belief.samples.states)


def test_the_papers_pgm_never_changes_its_particle_count():
    assert run_updates(PaperPGMFilter(n_particles=2000, n_components=2)) == [2000, 2000]
