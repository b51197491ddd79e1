"""The PGM's memory at large particle counts (issue 51): no step holds a second full-size copy of
the cloud. The reacquisition draws (``reacquire_factor`` x ``n_particles``) are made in chunks,
the prior particles are freed before them, the propagation writes over the filter's own particles
chunk by chunk, and the clustering, the group moments and the mixture densities work on blocks.
Each lean form gives the same numbers as the plain one.

The memory checks count what numpy allocates (tracemalloc) on a moderate cloud and compare the
peak with the arrays the step must return: a bound in bytes per particle, not a timing.
"""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from cistrack.model.belief import GaussianMixture, ParticleCloud
from cistrack.model.measurement import Measurement
from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.plugins.filters.ensemble_propagation import propagate_particles
from cistrack.plugins.filters.kalman_update import group_moments
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.pgm import prediction
from cistrack.plugins.filters.pgm.prediction import propagate_in_place
from cistrack.plugins.filters.pgm.reacquisition_particles import (DRAW_CHUNK, component_counts, draw_mixture,
                                                                   measurement_spread_sigma)

from .linear_models import LinearDynamics, LinearSensor

MB = 2**20


def _mixture(seed: int, m: int) -> GaussianMixture:
    r = np.random.default_rng(seed)
    w = r.random(m) ** 2
    w[m // 2] = 0.0  # an empty component
    a = r.normal(size=(m, 6, 6))
    return GaussianMixture(w / w.sum(), r.normal(size=(m, 6)) * 50.0, a @ np.transpose(a, (0, 2, 1)) + np.eye(6))


def _peak_above_start(fn, *args, **kwargs):
    """(fn's result, the most bytes numpy held during the call above what it held before)."""
    tracemalloc.start()
    try:
        start = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        out = fn(*args, **kwargs)
        return out, tracemalloc.get_traced_memory()[1] - start
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("n,chunk", [(0, 16), (1, 16), (999, 1000), (50_001, 4096), (50_001, 7)])
def test_chunked_reacquisition_draws_equal_one_draw(n, chunk):
    mix = _mixture(n, 5)
    ra, rb = np.random.default_rng(9), np.random.default_rng(9)
    want, got = mix.sample(n, ra), draw_mixture(mix, n, rb, chunk=chunk)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]) and got[1].dtype == want[1].dtype
    assert ra.random() == rb.random()  # the generator is left where one draw leaves it


def test_chunked_component_counts_equal_numpys_choice():
    w = np.array([0.1, 0.0, 0.35, 0.05, 0.5])
    ra, rb = np.random.default_rng(2), np.random.default_rng(2)
    want = np.bincount(ra.choice(5, size=123_457, p=w), minlength=5)
    assert np.array_equal(component_counts(w, 123_457, rb, chunk=1000), want)


def test_the_reacquisition_draws_hold_no_array_longer_than_a_chunk_besides_their_result():
    n, chunk = 400_000, 4096
    draw_mixture(_mixture(1, 6), 10, np.random.default_rng(0), chunk)
    (x, labels), peak = _peak_above_start(draw_mixture, _mixture(1, 6), n, np.random.default_rng(0), chunk)
    work = peak - x.nbytes - labels.nbytes
    assert work <= 8 * chunk * 48  # a few chunks of normals and uniforms; one (n,) float64 is 3.2 MB


def _reacquiring_filter(n: int) -> tuple[PGMFilter, Measurement]:
    """A PGM of ``n`` particles whose first update reacquires (the prior spreads over 500 noise
    sigmas) and draws 4 n particles."""
    sensor = LinearSensor(sigma=0.01)
    filt = PGMFilter(n_particles=n, n_components=4, reacquire_factor=4.0, reacquire_spread_sigma=100.0,
                     reanchor="off")
    x = np.random.default_rng(0).standard_normal((n, 6)) * np.array([5.0] * 3 + [1e-4] * 3)
    filt.initialize(ParticleCloud(x, 0.0), LinearDynamics(), sensor, np.random.default_rng(1))
    return filt, Measurement(0.0, np.array([0.01, -0.02]), 1e-4 * np.eye(2), sensor.names)


def test_a_reacquiring_update_holds_little_more_than_the_drawn_particles():
    small, z = _reacquiring_filter(2000)
    small.update(z)  # imports and compiled functions loaded before counting
    n = 300_000
    filt, z = _reacquiring_filter(n)
    _, peak = _peak_above_start(filt.update, z)
    drawn = filt.belief.samples.states.shape[0]
    assert drawn == 4 * n
    # the draws (48 bytes a particle) and their labels (8), and two chunks of normals: the prior
    # particles, their residuals and labels are freed before the draws (holding them is 7 MB more)
    assert peak <= drawn * 56 + 2 * DRAW_CHUNK * 48 + 1 * MB


def test_the_prediction_writes_over_the_filters_own_particles(monkeypatch):
    monkeypatch.setattr(prediction, "PROPAGATION_CHUNK", 10_000)
    _reacquiring_filter(20_000)[0].predict(1.0)  # code paths loaded before counting
    n = 200_000
    filt, _ = _reacquiring_filter(n)
    before = filt.belief.samples.states.copy()
    _, peak = _peak_above_start(filt.predict, 1.0)
    after = filt.belief.samples.states
    assert after.shape == before.shape and not np.array_equal(after, before)
    assert peak <= n * 8 + 10_000 * 6 * 8 * 8  # an alive flag a particle and a few chunks; not (n, 6)


def test_the_prediction_copies_particles_that_something_else_holds(monkeypatch):
    monkeypatch.setattr(prediction, "PROPAGATION_CHUNK", 1000)
    filt, _ = _reacquiring_filter(5000)
    held = filt.belief.samples.states  # a caller keeps the prior particles
    kept = held.copy()
    filt.predict(1.0)
    assert np.array_equal(held, kept)


@pytest.mark.parametrize("steps", [True, False])
def test_chunked_in_place_propagation_equals_one_call(steps, monkeypatch):
    from cistrack import units
    from cistrack.plugins.dynamics.cr3bp import CR3BP
    from cistrack.plugins.dynamics.orbit_catalog import ORBITS

    orbit, dyn = ORBITS["nrho-9-2"], CR3BP()
    sig = np.r_[[units.km_to_lu(3000.0)] * 3, [units.kms_to_vu(1e-2)] * 3]
    x0 = orbit.state + np.random.default_rng(3).normal(size=(1500, 6)) * sig  # some hit the Moon
    h0 = np.full(1500, 1e-3) if steps else None
    want = propagate_particles(dyn, x0.copy(), 0.0, 0.5 * orbit.period, "t", 0.01, np.random.default_rng(1),
                               None if h0 is None else h0.copy())
    x = x0.copy()
    monkeypatch.setattr(prediction, "PROPAGATION_CHUNK", 400)
    got = propagate_in_place(dyn, x, 0.0, 0.5 * orbit.period, "t", 0.01, np.random.default_rng(1),
                             None if h0 is None else h0.copy())
    assert not want[1].all()
    assert got[0] is x and np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert (got[2] is None and want[2] is None) or np.array_equal(got[2], want[2])


def test_group_moments_hold_one_group_at_a_time():
    n, m = 600_000, 6
    r = np.random.default_rng(4)
    x, d, labels = r.normal(size=(n, 6)), r.normal(size=(n, 2)), r.integers(0, m, size=n)
    group_moments(x[:100], d[:100], labels[:100], m)  # compiled before counting
    _, peak = _peak_above_start(group_moments, x, d, labels, m)
    largest = int(np.bincount(labels).max())
    # the largest group's rows of [x d] (64 bytes a row); all n rows of [x d] at once would be 64 n
    assert peak <= largest * 64 + 1 * MB


def test_a_group_larger_than_a_block_is_summed_in_blocks(monkeypatch):
    from cistrack.plugins.filters import kalman_update

    n = 600_000
    r = np.random.default_rng(7)
    x, d, labels = r.normal(size=(n, 6)), r.normal(size=(n, 2)), np.zeros(n, dtype=np.intp)
    with monkeypatch.context() as small:
        small.setattr(kalman_update, "GROUP_BLOCK_ROWS", 10)
        group_moments(x[:100], d[:100], labels[:100], 1)  # the block path compiled before counting
    _, peak = _peak_above_start(group_moments, x, d, labels, 1)
    # one block of GROUP_BLOCK_ROWS rows of [x d] (64 bytes a row), not all 600,000 rows (38 MB)
    assert peak <= kalman_update.GROUP_BLOCK_ROWS * 64 + 1 * MB


def test_kmeans_labels_every_particle_without_a_standardised_copy():
    n = 600_000
    x = np.random.default_rng(5).normal(size=(n, 6)) * np.logspace(-3, 3, 6)
    KMeansClusterer(n_components=6).cluster(x[:5000], np.random.default_rng(0))  # compiled before counting
    labels, peak = _peak_above_start(KMeansClusterer(n_components=6).cluster, x, np.random.default_rng(0))
    # the labels and their compaction (8 bytes a particle each) and blocks of 65,536 rows; the
    # standardised copy of the particles alone would be 48 n
    assert labels.shape == (n,) and peak <= n * 16 + 12 * MB


def test_mixture_density_blocks_equal_one_evaluation():
    mix = _mixture(7, 6)
    x = np.random.default_rng(6).normal(size=(200_003, 6)) * 40.0
    blocks = np.concatenate([mix.logpdf(x[a:a + 1000]) for a in range(0, x.shape[0], 1000)])
    assert np.array_equal(mix.logpdf(x), blocks)


def _plain_spread(res, R):
    L = np.linalg.cholesky(R)
    plain = np.cov(np.linalg.solve(L, (res - res.mean(axis=0)).T))
    return float(np.sqrt(np.linalg.eigvalsh(plain).max()))


@pytest.mark.parametrize("n", [100_003, 200_003])  # held whole up to SPREAD_WHOLE_ROWS, in blocks above
def test_the_spread_whitened_in_chunks_equals_the_plain_formula(n):
    from cistrack.plugins.filters.pgm.reacquisition_particles import SPREAD_WHOLE_ROWS

    r = np.random.default_rng(12)
    res = r.normal(size=(n, 2)) * np.array([3e-3, 4e-5]) + 0.2
    R = np.array([[4.0, 1.2], [1.2, 1.0]]) * 1e-10
    if n <= SPREAD_WHOLE_ROWS:  # the numbers runs of up to 131,072 particles have always had
        assert measurement_spread_sigma(res, R) == _plain_spread(res, R)
    else:
        assert measurement_spread_sigma(res, R) == pytest.approx(_plain_spread(res, R), rel=1e-12)


def test_the_spread_of_many_residuals_holds_no_whitened_copy_of_them():
    res = np.random.default_rng(13).normal(size=(400_000, 2))
    measurement_spread_sigma(res[:10], np.eye(2))
    _, peak = _peak_above_start(measurement_spread_sigma, res, np.eye(2))
    # a few chunks of DRAW_CHUNK rows; holding the whitened residuals whole took res.nbytes more
    assert peak <= 4 * MB
