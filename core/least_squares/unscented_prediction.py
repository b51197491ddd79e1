"""A fitted orbit's covariance at other times by the unscented transform: the fit's state and
2n sigma points ``x ± sqrt(n) s_i`` (``s_i`` the columns of a square root of the covariance, n = 6)
propagated with the full nonlinear dynamics, and their spread about the propagated state, with
equal weights 1/(2n) (the symmetric sigma-point set of the cubature rule).

Where the flow bends within the covariance's extent (a close lunar flyby: the thinnest direction
of a fitted covariance is metres wide there, and the second-order terms of the flow move the
orbit by more than that), the linear map ``Phi P Phi^T`` describes a covariance several times
too thin, and the truth falls outside it; the sigma points follow the bend (issue 31 note,
session 13: 9:2 NRHO campaign seed 62, perilune at 110 km, truth's Mahalanobis^2 26.1 under the
linear covariance, 6.0 under this one; a 2,000-sample Monte Carlo of the fit covariance 6.03).
On a linear stretch of the orbit the two agree (tests/fit/test_unscented_prediction.py).
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import PropagationError, StateError
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["sigma_points", "unscented_covariances"]


def sigma_points(state: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """The 2n sigma points (2n, n) of a mean ``state`` (n,) and ``covariance`` (n, n): ``state +
    sqrt(n) s_i`` then ``state - sqrt(n) s_i``, ``s_i`` the columns of ``V sqrt(max(w, 0))`` from the
    symmetric eigendecomposition ``V diag(w) V^T`` (a nearly singular fitted covariance, whose
    Cholesky factor may not exist in floating point, still has this square root). Their sample
    covariance about ``state`` with weights 1/(2n) is ``covariance``. Raises
    :class:`~cistrack.errors.StateError` for a covariance that is not finite, square and symmetric."""
    x = np.asarray(state, dtype=float).reshape(-1)
    p = np.asarray(covariance, dtype=float)
    n = x.size
    if p.shape != (n, n) or not np.all(np.isfinite(p)) or not np.all(np.isfinite(x)):
        raise StateError(f"sigma points: need a finite state ({n},) and covariance ({n}, {n}), got shapes "
                         f"{x.shape} and {p.shape}")
    scale = max(float(np.max(np.abs(p))), np.finfo(float).tiny)
    if np.max(np.abs(p - p.T)) > 1e-9 * scale:
        raise StateError("sigma points: the covariance is not symmetric")
    w, v = np.linalg.eigh(0.5 * (p + p.T))
    if np.min(w) < -1e-9 * max(float(np.max(w)), 0.0):
        raise StateError(f"sigma points: the covariance is not positive semi-definite (eigenvalue {np.min(w):.3g})")
    root = v * np.sqrt(np.clip(w, 0.0, None))  # columns s_i, root @ root.T == p
    delta = np.sqrt(n) * root.T
    return np.vstack([x + delta, x - delta])


def _side(dynamics: Dynamics, batch: np.ndarray, t0: float, side: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 2n+1, n) of ``batch`` propagated to the times ``side`` (one direction), and
    whether every orbit of the batch is alive at each of them (K,)."""
    prop = dynamics.propagate(batch, t0, side)
    states = np.asarray(prop.states, dtype=float)
    alive = np.ones(side.size, dtype=bool)
    if not bool(np.all(prop.alive)):
        hit = np.min(np.asarray(prop.impact_time, dtype=float)[~np.asarray(prop.alive)])
        alive = (side < hit) if side[-1] >= t0 else (side > hit)
    return states, alive


def unscented_covariances(dynamics: Dynamics, state: np.ndarray, covariance: np.ndarray, t0: float,
                          times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Covariances (K, n, n) at ``times`` (K,) TU of the orbit ``state`` (n,) [LU, VU] with
    ``covariance`` (n, n) at ``t0`` (TU), by the unscented transform (module docstring), and whether
    each is one (K,) bool: False at the times on and after a sigma-point orbit hit a body or failed
    to propagate (there the caller keeps its linear covariance; those entries are NaN).

    The state and the sigma points go through the dynamics' ``propagate`` in one call per
    direction, so that the spread is measured about a state integrated exactly as they are."""
    tt = np.asarray(times, dtype=float).reshape(-1)
    x = np.asarray(state, dtype=float).reshape(-1)
    n = x.size
    batch = np.vstack([x[None], sigma_points(x, covariance)])
    covs = np.full((tt.size, n, n), np.nan)
    valid = np.zeros(tt.size, dtype=bool)
    at = tt == t0
    covs[at] = np.asarray(covariance, dtype=float)
    valid[at] = True
    for forward in (True, False):
        mask = tt > t0 if forward else tt < t0
        if not np.any(mask):
            continue
        side, k = np.unique(tt[mask], return_inverse=True)  # distinct times, increasing
        if not forward:  # propagated backward: decreasing times
            side, k = side[::-1], side.size - 1 - k
        try:
            states, alive = _side(dynamics, batch, t0, side)
        except PropagationError:
            continue  # a sigma point's integration failed (step limit): linear covariances there
        d = states[:, 1:, :] - states[:, :1, :]          # (K, 2n, n) about the propagated state
        c = np.einsum("kij,kil->kjl", d, d) / (2 * n)
        ok = alive[k]
        rows = np.flatnonzero(mask)[ok]
        covs[rows] = 0.5 * (c[k[ok]] + np.transpose(c[k[ok]], (0, 2, 1)))
        valid[rows] = True
    return covs, valid
