"""The belief of a single-Gaussian filter (UKF, EnKF)."""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud, regularize_covariance

__all__ = ["single_gaussian", "gaussian_belief"]


def single_gaussian(mean: np.ndarray, cov: np.ndarray) -> GaussianMixture:
    """A mixture of one component: mean (d,), covariance (d, d) made symmetric positive definite."""
    return GaussianMixture(np.ones(1), np.asarray(mean, dtype=float)[None],
                           regularize_covariance(np.asarray(cov, dtype=float), 1e-12)[None])


def gaussian_belief(epoch: float, mean: np.ndarray, cov: np.ndarray, n_samples: int,
                    rng: np.random.Generator) -> Belief:
    """Belief with ``n_samples`` draws from N(mean, cov) as its samples."""
    mix = single_gaussian(mean, cov)
    x, labels = mix.sample(n_samples, rng)
    return Belief(float(epoch), mix, ParticleCloud(x, float(epoch), None, labels))
