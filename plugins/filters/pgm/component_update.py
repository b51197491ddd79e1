"""Per-component measurement updates of a Gaussian mixture prior: the PGM's ``pgm-update`` step.

Two ways to condition each component N(mu_i, P_i) of a clustered prior on a measurement z:

- ``ensemble`` (the paper's PGM): a Kalman update from the sample cross-covariances of the
  component's particles with their predicted measurements. It linearises h statistically over
  the whole component.
- ``iterated``: the iterated posterior linearisation (IPLF, :mod:`.posterior_linearization`) of
  each component's Gaussian, with h re-linearised over the component's current posterior until
  the mean stops moving. When a component is much wider than the 1.5 arcsec noise and h is
  curved across it (the first pass, after uniform-range IOD: tens of thousands of km of range
  uncertainty), the prior-wide linearisation puts the posterior beside the sliver of states that
  agree with z, with a covariance too small there; the iterated update does not.

Both return the posterior means (M, d), covariances (M, d, d) and each component's predictive
log-likelihood log p(z | component) (M,), which reweights the components. :class:`IteratedUpdate`
and :class:`EnsembleUpdate` are the two as registered components (kind ``pgm-update``).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from cistrack.interfaces.component import check_choice, check_int
from cistrack.interfaces.pgm_steps import ComponentUpdate
from cistrack.model.belief import regularize_covariance

from ..kalman_update import GroupMoments, component_posterior, gaussian_log_likelihood, kalman_gains
from ..posterior_linearization import MAX_UPDATE_ITERATIONS, posterior_linearization_updates
from ..sigma_points import MerweSigmaPoints

__all__ = ["ensemble_component_update", "iterated_component_update", "EnsembleUpdate", "IteratedUpdate",
           "COMPONENT_LIKELIHOODS"]

COMPONENT_LIKELIHOODS = ("posterior", "prior")
"""Where the iterated update linearises h for the components' likelihoods."""


def ensemble_component_update(moments: GroupMoments, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's update from particle moments (``moments`` with measurement columns)."""
    gains = kalman_gains(moments, R)
    means, covs = component_posterior(moments, gains)
    return means, covs, gaussian_log_likelihood(gains.nu, gains.S)


def iterated_component_update(means: np.ndarray, covs: np.ndarray,
                              residual_to_z: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
                              max_iterations: int = 10, tolerance: float = 1e-3,
                              likelihood: str = "posterior") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IPLF update of each component N(means[i] (d,), covs[i] (d, d)).

    residual_to_z : states (K, d) -> h(states) - z (K, m), angles wrapped.
    likelihood : "posterior" scores each component with h linearised over its posterior (where
        the states that explain z are), "prior" with the one-shot (prior-wide) linearisation.
    Returns means (M, d), covariances (M, d, d), log-likelihoods (M,).
    """
    d = means.shape[1]
    points = MerweSigmaPoints(d, alpha=1.0, beta=2.0, kappa=0.0)  # filterpy's points, without importing filterpy
    # all components at once: each iteration is one sensor call on the 2d+1 points of every
    # component still iterating
    results = posterior_linearization_updates(points, means, covs, residual_to_z, R,
                                              max_iterations=max_iterations, tolerance=tolerance)
    out_m = np.array([res.x for res in results]).reshape(means.shape)
    out_p = np.array([res.P for res in results]).reshape(covs.shape)
    if likelihood == "posterior":
        nus, Ss = [res.innovation_final for res in results], [res.S_final for res in results]
    else:
        nus, Ss = [res.innovation for res in results], [res.S for res in results]
    loglik = gaussian_log_likelihood(np.array(nus), np.array(Ss))
    return out_m, regularize_covariance(out_p, 1e-12), loglik


class IteratedUpdate(ComponentUpdate):
    """Iterated posterior linearisation of each component's Gaussian, re-linearised until its mean
    stops moving (the PGM's default update).

    Parameters
    ----------
    update_iterations : int
        Most posterior linearisations per component and measurement, 1 to 1000.
    component_likelihood : str
        What reweights the components: "posterior" (the measurement likelihood with h linearised
        over the component's posterior) or "prior" (over its prior).
    """

    def __init__(self, update_iterations: int = 10, component_likelihood: str = "posterior"):
        self.update_iterations = check_int(self, "update_iterations", update_iterations, minimum=1,
                                           maximum=MAX_UPDATE_ITERATIONS)
        self.component_likelihood = check_choice(self, "component_likelihood", component_likelihood,
                                                 COMPONENT_LIKELIHOODS)

    def update(self, moments: GroupMoments, residuals: Callable[[np.ndarray], np.ndarray],
               R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Means (M, d), covariances (M, d, d), log-likelihoods (M,) of the components ``moments``."""
        return iterated_component_update(moments.mean_x, moments.pxx, residuals, R,
                                         max_iterations=self.update_iterations, likelihood=self.component_likelihood)


class EnsembleUpdate(ComponentUpdate):
    """The paper's Kalman update of each component from its particles' sample cross-covariances
    with their predicted measurements."""

    uses_particles = True

    def update(self, moments: GroupMoments, residuals: Callable[[np.ndarray], np.ndarray],
               R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Means (M, d), covariances (M, d, d), log-likelihoods (M,) from ``moments`` with measurement columns."""
        return ensemble_component_update(moments, R)
