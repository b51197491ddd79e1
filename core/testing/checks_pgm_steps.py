"""Conformance checks for the PGM's swappable steps (kinds ``pgm-update``, ``pgm-draw``,
``pgm-prediction``, ``pgm-kernel``, ``pgm-reanchor``).

The component update is held to a closed form: with a linear measurement h(x) = H x every
correct conditioning of a Gaussian component is the Kalman filter's, and its predictive
likelihood is N(z; H mean, H P H^T + R).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack.interfaces.pgm_steps import (ClusteredParticles, ComponentUpdate, KernelRun, KernelUpdate,
                                           ParticlePrediction, PosteriorDraw, Reanchor, ReanchorRun)
from cistrack.model.belief import GaussianMixture
from cistrack.testing.check_support import no_global_random_state, require
from cistrack.testing.fixtures import nrho_states

__all__ = ["PGM_STEP_CHECKS"]

_D, _M = 6, 2  # state dimension, measured components


def _linear_problem(seed: int = 7) -> SimpleNamespace:
    """Two Gaussian components (LU, VU scale), a linear measurement H (2, 6), z and R."""
    rng = np.random.default_rng(seed)
    means = rng.normal(0.0, 1e-3, (2, _D))
    a = rng.normal(0.0, 1e-4, (2, _D, _D))
    covs = a @ np.transpose(a, (0, 2, 1)) + 1e-10 * np.eye(_D)
    H = rng.normal(0.0, 1.0, (_M, _D))
    R = np.diag([1e-9, 2e-9])
    z = H @ means[0] + rng.normal(0.0, 1e-4, _M)
    return SimpleNamespace(means=means, covs=covs, H=H, R=R, z=z)


def _moments(p: SimpleNamespace) -> SimpleNamespace:
    """The moments a PGM hands its update, exact for the linear problem (no sampling noise)."""
    ht = p.H.T
    return SimpleNamespace(counts=np.array([500, 500]), mean_x=p.means.copy(), pxx=p.covs.copy(),
                           mean_d=p.means @ ht - p.z, pxd=p.covs @ ht, pdd=p.H @ p.covs @ ht)


def _kalman(p: SimpleNamespace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact posterior means (2, 6), covariances (2, 6, 6) and log-likelihoods (2,)."""
    out_m, out_p, loglik = [], [], []
    for mean, cov in zip(p.means, p.covs):
        S = p.H @ cov @ p.H.T + p.R
        K = cov @ p.H.T @ np.linalg.inv(S)
        nu = p.z - p.H @ mean
        out_m.append(mean + K @ nu)
        out_p.append(cov - K @ S @ K.T)
        loglik.append(-0.5 * (nu @ np.linalg.solve(S, nu) + np.linalg.slogdet(2 * np.pi * S)[1]))
    return np.array(out_m), np.array(out_p), np.array(loglik)


def check_is_component_update(c) -> None:
    require(isinstance(c, ComponentUpdate), f"{type(c).__name__} does not derive from "
            "cistrack.interfaces.pgm_steps.ComponentUpdate")


def check_update_is_kalman_for_linear_measurements(c) -> None:
    """Conditioning on h(x) = H x gives the Kalman posterior and likelihood (rtol 1e-6)."""
    p = _linear_problem()
    with no_global_random_state("update"):
        means, covs, loglik = c.update(_moments(p), lambda x: np.atleast_2d(x) @ p.H.T - p.z, p.R)
    want_m, want_p, want_l = _kalman(p)
    require(np.shape(means) == (2, _D) and np.shape(covs) == (2, _D, _D) and np.shape(loglik) == (2,),
            f"update() returned shapes {np.shape(means)}, {np.shape(covs)}, {np.shape(loglik)}; "
            "expected (M, d), (M, d, d), (M,) = (2, 6), (2, 6, 6), (2,)")
    scale = np.sqrt(np.diagonal(want_p, axis1=1, axis2=2))
    err_m = float(np.max(np.abs(means - want_m) / scale))
    require(err_m < 1e-6, f"posterior means differ from the Kalman filter's by {err_m:.2e} sigma")
    err_p = float(np.max(np.abs(covs - want_p)) / np.max(np.abs(want_p)))
    require(err_p < 1e-6, f"posterior covariances differ from the Kalman filter's (relative {err_p:.2e})")
    err_l = float(np.max(np.abs(np.asarray(loglik) - want_l)))
    require(err_l < 1e-6, f"log-likelihoods differ from log N(z; H mean, H P H^T + R) by {err_l:.2e}")


def _clustered_prior(n: int = 400, seed: int = 3) -> tuple[ClusteredParticles, GaussianMixture]:
    p = _linear_problem()
    rng = np.random.default_rng(seed)
    labels = np.repeat([0, 1], n // 2)
    states = np.concatenate([rng.multivariate_normal(m, c, n // 2) for m, c in zip(p.means, p.covs)])
    means = np.array([states[labels == k].mean(axis=0) for k in (0, 1)])
    covs = np.array([np.cov(states[labels == k].T) for k in (0, 1)])
    post_m, post_p, _ = _kalman(p)
    return ClusteredParticles(states, labels, means, covs), GaussianMixture(np.array([0.3, 0.7]), post_m, post_p)


def check_is_posterior_draw(c) -> None:
    require(isinstance(c, PosteriorDraw), f"{type(c).__name__} does not derive from "
            "cistrack.interfaces.pgm_steps.PosteriorDraw")


def check_draw_shapes_and_seed(c) -> None:
    """``draw`` gives (n, d) finite particles and (n,) labels in [0, M), the same for the same seed."""
    prior, post = _clustered_prior()
    n = prior.states.shape[0]
    with no_global_random_state("draw"):
        x, lab = c.draw(prior, post, n, np.random.default_rng(11))
    x2, lab2 = c.draw(prior, post, n, np.random.default_rng(11))
    require(np.shape(x) == (n, _D) and np.shape(lab) == (n,), f"draw() returned shapes {np.shape(x)}, "
            f"{np.shape(lab)}; expected (n, d), (n,) = ({n}, {_D}), ({n},)")
    require(np.all(np.isfinite(x)), "draw() returned non-finite particles")
    require(np.all((np.asarray(lab) >= 0) & (np.asarray(lab) < 2)), "draw() labels must lie in [0, M)")
    require(np.array_equal(x, x2) and np.array_equal(lab, lab2), "draw() with the same seed gave different particles")


def check_draw_follows_the_posterior(c) -> None:
    """Each component's drawn particles centre on that component's posterior mean (within 5 of
    its standard errors per coordinate)."""
    prior, post = _clustered_prior(n=4000)
    x, lab = c.draw(prior, post, 4000, np.random.default_rng(5))
    lab = np.asarray(lab)
    for k in range(post.n_components):
        sel = x[lab == k]
        require(sel.shape[0] > 1, f"draw() gave no particles to posterior component {k}")
        se = np.sqrt(np.diagonal(post.covariances[k]) / sel.shape[0])
        off = float(np.max(np.abs(sel.mean(axis=0) - post.means[k]) / se))
        require(off < 5.0, f"particles of component {k} centre {off:.1f} standard errors from its posterior mean")


def check_is_particle_prediction(c) -> None:
    require(isinstance(c, ParticlePrediction), f"{type(c).__name__} does not derive from "
            "cistrack.interfaces.pgm_steps.ParticlePrediction")


def check_prediction_moves_particles(c) -> None:
    """Particles on the 9:2 NRHO carried 0.05 TU by the CR3BP: (N, 6) finite, ``alive`` (N,) bool."""
    from cistrack.plugin.registry import default_registry

    x0 = nrho_states(8)
    dyn = default_registry().create("dynamics", "cr3bp")
    with no_global_random_state("predict"):
        x, alive, _ = c.predict(dyn, x0.copy(), 0.0, 0.05, np.random.default_rng(1), None, "check")
    require(np.shape(alive) == (8,) and np.asarray(alive).dtype == bool, f"alive has shape {np.shape(alive)}, expected (8,) bool")
    require(np.shape(x) == (int(np.count_nonzero(alive)), _D), f"predict() returned {np.shape(x)} for {np.count_nonzero(alive)} survivors")
    require(np.all(np.isfinite(x)) and not np.allclose(x, x0[np.asarray(alive)]), "predict() did not move the particles")


def check_kernel_start(c) -> None:
    require(isinstance(c, KernelUpdate), f"{type(c).__name__} does not derive from cistrack.interfaces.pgm_steps.KernelUpdate")
    run = c.start()
    require(run is None or isinstance(run, KernelRun), f"start() returned {type(run).__name__}, not a KernelRun or None")
    require(run is None or c.start() is not run, "start() must give a fresh state for every run")


def check_reanchor_start(c) -> None:
    require(isinstance(c, Reanchor), f"{type(c).__name__} does not derive from cistrack.interfaces.pgm_steps.Reanchor")
    run = c.start()
    require(run is None or isinstance(run, ReanchorRun), f"start() returned {type(run).__name__}, not a ReanchorRun or None")
    require(run is None or c.start() is not run, "start() must give a fresh state for every run")


PGM_STEP_CHECKS: dict[str, list] = {
    "pgm-update": [("is_component_update", check_is_component_update),
                   ("update_is_kalman_for_linear_measurements", check_update_is_kalman_for_linear_measurements)],
    "pgm-draw": [("is_posterior_draw", check_is_posterior_draw), ("draw_shapes_and_seed", check_draw_shapes_and_seed),
                 ("draw_follows_the_posterior", check_draw_follows_the_posterior)],
    "pgm-prediction": [("is_particle_prediction", check_is_particle_prediction),
                       ("prediction_moves_particles", check_prediction_moves_particles)],
    "pgm-kernel": [("kernel_start", check_kernel_start)],
    "pgm-reanchor": [("reanchor_start", check_reanchor_start)],
}
