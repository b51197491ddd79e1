"""The truth's highest-density level is scored under the belief's own density, whatever its samples."""
import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.evaluation.metrics import step_metrics
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud


def _gaussian_belief_with_samples(samples: np.ndarray) -> Belief:
    """A single unit Gaussian in 6-D carrying the given samples (as an EnKF carries its ensemble)."""
    mix = GaussianMixture(np.ones(1), np.zeros((1, 6)), np.eye(6)[None])
    return Belief(0.0, mix, ParticleCloud(samples, 0.0))


def _heavy_tailed(n: int, seed: int) -> np.ndarray:
    """Student-t draws with 2 degrees of freedom: unit scale, far heavier tails than N(0, I)."""
    rng = np.random.default_rng(seed)
    return rng.standard_t(2, size=(n, 6))


def test_a_single_gaussian_is_scored_by_the_chi_square_of_the_truths_nees():
    truth = np.array([3.0, -2.0, 1.0, 0.5, 0.0, 2.0])
    level = step_metrics(_gaussian_belief_with_samples(_heavy_tailed(2000, 1)), truth)["hdr_level"]
    assert level == pytest.approx(chi2.cdf(truth @ truth, 6), rel=1e-12)


def test_a_truth_far_outside_the_gaussian_is_outside_its_region_however_heavy_the_samples_tails():
    truth = np.full(6, 40.0 ** 0.5 / 6 ** 0.5)  # NEES 40: outside the 0.997 region of chi-square(6)
    level = step_metrics(_gaussian_belief_with_samples(_heavy_tailed(2000, 2)), truth)["hdr_level"]
    assert level > 0.999


def test_a_mixture_of_several_components_is_scored_by_its_own_draws():
    mix = GaussianMixture(np.array([0.5, 0.5]), np.array([[-3.0] + [0.0] * 5, [3.0] + [0.0] * 5]),
                          np.stack([np.eye(6)] * 2))
    draws, labels = mix.sample(4000, np.random.default_rng(3))
    belief = Belief(0.0, mix, ParticleCloud(draws, 0.0, None, labels))
    truths, _ = mix.sample(300, np.random.default_rng(4))
    levels = np.array([step_metrics(belief, t)["hdr_level"] for t in truths])
    assert abs(levels.mean() - 0.5) < 0.06  # uniform for a truth drawn from the belief
