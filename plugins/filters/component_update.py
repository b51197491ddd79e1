"""Per-component measurement updates of a Gaussian mixture prior (used by the PGM filter).

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
log-likelihood log p(z | component) (M,), which reweights the components.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from cistrack.model.belief import regularize_covariance

from .kalman_update import GroupMoments, component_posterior, gaussian_log_likelihood, kalman_gains
from .posterior_linearization import posterior_linearization_update
from .sigma_points import MerweSigmaPoints

__all__ = ["ensemble_component_update", "iterated_component_update"]


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
    m, d = means.shape
    points = MerweSigmaPoints(d, alpha=1.0, beta=2.0, kappa=0.0)  # filterpy's points, without importing filterpy
    out_m = np.empty_like(means)
    out_p = np.empty_like(covs)
    nus, Ss = [], []
    for i in range(m):  # loop over components (few); each iteration is one sensor call on 2d+1 points
        res = posterior_linearization_update(points, means[i], covs[i], residual_to_z, R,
                                             max_iterations=max_iterations, tolerance=tolerance)
        out_m[i], out_p[i] = res.x, res.P
        if likelihood == "posterior":
            nus.append(res.innovation_final)
            Ss.append(res.S_final)
        else:
            nus.append(res.innovation)
            Ss.append(res.S)
    loglik = gaussian_log_likelihood(np.array(nus), np.array(Ss))
    return out_m, regularize_covariance(out_p, 1e-12), loglik
