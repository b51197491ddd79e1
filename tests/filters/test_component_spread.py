"""Moment-preserving shrinkage of the PGM's clustered components (component_spread.py)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import GaussianMixture, ParticleCloud
from cistrack.errors import ParameterError
from cistrack.plugins.filters.pgm.component_spread import shrink_components
from cistrack.plugins.filters.pgm import PaperPGMFilter, PGMFilter

from .linear_models import LinearDynamics, LinearSensor, filter_beside_kalman


def _mixture(seed=0, m=4, d=3):
    rng = np.random.default_rng(seed)
    w = rng.dirichlet(np.ones(m))
    means = rng.normal(size=(m, d)) * 3.0
    a = rng.normal(size=(m, d, d))
    covs = a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(d)
    return w, means, covs


@pytest.mark.parametrize("kept", [0.0, 0.3, 0.7, 1.0])
def test_shrinking_keeps_the_mixture_mean_and_covariance(kept):
    w, means, covs = _mixture()
    before = GaussianMixture(w, means, covs)
    after = GaussianMixture(w, *shrink_components(w, means, covs, kept))
    np.testing.assert_allclose(after.mean, before.mean, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(after.covariance, before.covariance, rtol=1e-10, atol=1e-12)


def test_shrinking_fully_gives_every_component_the_moment_matched_gaussian():
    w, means, covs = _mixture()
    mix = GaussianMixture(w, means, covs)
    m2, c2 = shrink_components(w, means, covs, 0.0)
    np.testing.assert_allclose(m2, np.broadcast_to(mix.mean, m2.shape), atol=1e-12)
    between = mix.covariance - np.einsum("i,ijk->jk", w, covs)
    np.testing.assert_allclose(c2 - covs, np.broadcast_to(between, c2.shape), atol=1e-10)


def _pgm_against_kalman(filt, sigma=0.02, seed=0):
    """Final per-axis sd ratio PGM / exact Kalman after 15 updates of one measured coordinate."""
    m0 = np.array([1.0, 2.0, -0.5, 0.1, -0.1, 0.05])
    p0 = np.diag([0.5, 0.5, 0.5, 0.05, 0.05, 0.05])
    p0[0, 3] = p0[3, 0] = 0.03
    times = np.arange(1, 16) * 0.3
    sensor = LinearSensor(sigma=sigma, coords=(0,))
    _, P = filter_beside_kalman(filt, m0, p0, times, sensor, np.random.default_rng(seed),
                                np.random.default_rng(seed + 100))
    return np.sqrt(np.diag(filt.belief.mixture.covariance) / np.diag(P))


SEEDS = range(4)  # one run's final spread varies by ~10% with the resampling; average four


def test_pgm_with_kmeans_cells_grows_overconfident_over_repeated_updates_without_shrinkage():
    # the mechanism the shrinkage answers: truncated cells claim too small a conditional spread
    ratio = np.mean([_pgm_against_kalman(PGMFilter(n_particles=10000, n_components=6, kept_spread=1.0),
                                         seed=s) for s in SEEDS], axis=0)
    assert ratio.min() < 0.92, ratio


def test_default_pgm_keeps_the_kalman_spread_over_repeated_updates():
    ratio = np.mean([_pgm_against_kalman(PGMFilter(n_particles=10000, n_components=6), seed=s)
                     for s in SEEDS], axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=0.08)


def test_pgm_shrinks_by_default_and_pgm_paper_does_not():
    assert PGMFilter().kept_spread == 0.7
    assert PaperPGMFilter().kept_spread == 1.0


@pytest.mark.parametrize("value", [-0.1, 1.5])
def test_pgm_rejects_a_kept_spread_outside_zero_to_one(value):
    with pytest.raises(ParameterError, match="kept_spread"):
        PGMFilter(kept_spread=value)


_APART = np.array([1.0, 0.0, 1.0, 1.0, 1.0, 1.0])  # the hypotheses differ in every coordinate but 1


def _two_hypotheses(seed=0, n=4000, half_gap=5.0, sd=0.3):
    """Particles (2n, 6) in two separated blobs at -half_gap and +half_gap along _APART."""
    rng = np.random.default_rng(seed)
    x = rng.normal(scale=sd, size=(2 * n, 6))
    x[:n] -= half_gap * _APART
    x[n:] += half_gap * _APART
    return x


def _share_in_the_gap(filt, seed=0, sigma=1e-4):
    """Share of the PGM's posterior particles between two separated hypotheses after one update
    by a measurement (of coordinate 1, noise ``sigma``) that both explain equally. The prior's
    predicted measurements spread over 0.3 / sigma noise sigmas (3,000 by default)."""
    x = _two_hypotheses(seed)
    sensor = LinearSensor(sigma=sigma, coords=(1,))
    filt.initialize(ParticleCloud(x, 0.0), LinearDynamics(), sensor, np.random.default_rng(seed))
    meas = sensor.simulate(np.zeros((1, 6)), np.array([1e-9]), np.random.default_rng(seed + 1))[0]
    filt.predict(meas.t)
    filt.update(meas)
    along = filt.belief.samples.states @ _APART / np.sqrt(5.0)   # blob centres at +-11.2, sd 0.3
    return float(np.mean(np.abs(along) < 8.0))


def test_shrinking_while_reacquiring_drags_separated_hypotheses_into_the_gap_between_them():
    # the failure after a long gap: shrinkage pulls both hypotheses toward their empty middle
    share = _share_in_the_gap(PGMFilter(n_particles=8000, n_components=6, kept_spread=0.7,
                                        shrink_spread_sigma=1e9))
    assert share > 0.1, share


def test_default_pgm_does_not_shrink_while_reacquiring_and_leaves_the_gap_empty():
    filt = PGMFilter(n_particles=8000, n_components=6)
    share = _share_in_the_gap(filt)
    assert filt.diagnostics["components_shrunk"] == 0.0
    assert share < 1e-3, share


def test_default_pgm_shrinks_once_the_predicted_spread_is_under_the_threshold():
    filt = PGMFilter(n_particles=8000, n_components=6)
    _share_in_the_gap(filt, sigma=0.05)   # the cloud's predicted measurements spread over 6 sigmas
    assert filt.diagnostics["components_shrunk"] == 1.0


@pytest.mark.parametrize("value", [0.0, -5.0])
def test_pgm_rejects_a_shrink_spread_threshold_that_is_not_positive(value):
    with pytest.raises(ParameterError, match="shrink_spread_sigma"):
        PGMFilter(shrink_spread_sigma=value)
