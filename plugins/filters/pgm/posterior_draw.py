"""The PGM's ``pgm-draw`` step: where its posterior particles come from.

``transform`` (the default) carries each cluster's own particles into its component's posterior
(:mod:`.posterior_transform`), so the cloud keeps its non-Gaussian shape; ``gaussian`` (the
paper's) draws them from the posterior mixture.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.pgm_steps import ClusteredParticles, PosteriorDraw
from cistrack.model.belief import GaussianMixture

from .posterior_transform import transform_clusters

__all__ = ["GaussianDraw", "TransformDraw"]


class TransformDraw(PosteriorDraw):
    """Each cluster's particles mapped affinely onto its component's posterior (the PGM's default:
    the cloud keeps its shape); a component that keeps more particles than its cluster holds gets
    the rest as Gaussian draws."""

    def draw(self, prior: ClusteredParticles, posterior: GaussianMixture, n: int,
             rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` particles (n, d) and their components (n,); raises numpy's LinAlgError when a
        cluster's covariance cannot be factorised."""
        return transform_clusters(prior.states, prior.labels, prior.means, prior.covariances, posterior, n, rng)


class GaussianDraw(PosteriorDraw):
    """Draws from the posterior Gaussian mixture (the paper's PGM)."""

    def draw(self, prior: ClusteredParticles, posterior: GaussianMixture, n: int,
             rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws (n, d) from ``posterior`` and their components (n,)."""
        return posterior.sample(n, rng)
