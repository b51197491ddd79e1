"""What a recording keeps of a large belief: a capped, seeded subsample of the particles that keeps
every mixture component represented, and the heaviest components' ellipsoids.

A recording of 10,000 particles at each of ~200 events is tens of MB and loads slowly in a
software-rendered viewer; a few thousand particles per event show the cloud as well. Pure numpy;
the recorder applies these indices before logging.
"""
from __future__ import annotations

import numpy as np

__all__ = ["MIN_SHARE", "component_quotas", "heaviest_components", "subsample_indices"]

MIN_SHARE = 0.02
"""Each component present keeps at least this fraction of the particles logged (at least one
particle, at most all of its own), so a light component is not drawn away."""


def component_quotas(counts: np.ndarray, max_points: int) -> np.ndarray:
    """How many particles of each group to keep when ``max_points`` of ``sum(counts)`` are kept.

    Parameters
    ----------
    counts : (K,) int, particles per group (component), each >= 1
    max_points : int >= 1, the total kept (at most ``sum(counts)``)

    Returns
    -------
    (K,) int
        Sums to ``min(max_points, sum(counts))``: each group's share in proportion to its count,
        raised to ``min(count, max(1, MIN_SHARE * max_points))`` for a group whose share is less
        (the other groups share the rest in proportion; largest remainders round). With more
        groups than points, one particle for each of the largest groups.
    """
    c = np.asarray(counts, dtype=np.int64)
    total = int(min(max_points, c.sum()))
    if len(c) > total:
        q = np.zeros_like(c)
        q[np.argsort(-c, kind="stable")[:total]] = 1
        return q
    floor = np.minimum(c, max(1, int(MIN_SHARE * max_points)))
    if floor.sum() > total:
        floor = np.minimum(c, 1)
    fixed = np.zeros(len(c), dtype=bool)
    for _ in range(len(c)):  # a group raised to its floor leaves less to share: settle in rounds
        left = total - int(floor[fixed].sum())
        share = np.where(fixed, floor, c * (left / max(int(c[~fixed].sum()), 1)))
        low = ~fixed & (share < floor)
        if not low.any():
            break
        fixed |= low
    q = np.where(fixed, floor, np.floor(share)).astype(np.int64)
    short = total - int(q.sum())
    if short > 0:
        order = np.argsort(-np.where(fixed, -1.0, share - np.floor(share)), kind="stable")
        q[order[:short]] += 1
    return q


def subsample_indices(n: int, max_points: int, seed: int = 0,
                      labels: np.ndarray | None = None) -> np.ndarray | None:
    """Rows kept when a cloud of ``n`` particles is capped at ``max_points``.

    Returns None when nothing is dropped, else ``max_points`` sorted distinct indices. One random
    order of the rows, from ``numpy.random.default_rng([seed, n])``, picks them: the first
    ``max_points`` rows in that order, or with ``labels`` ((n,) component of each particle) the
    first rows of each component up to its quota (:func:`component_quotas`), so every component
    keeps particles. The same ``n``, ``seed`` and labels give the same rows at every step.
    """
    if n <= max_points:
        return None
    order = np.random.default_rng([int(seed), int(n)]).permutation(n)
    if labels is None:
        return np.sort(order[:max_points])
    lab = np.asarray(labels).reshape(n)[order]
    groups, inverse, counts = np.unique(lab, return_inverse=True, return_counts=True)
    quota = component_quotas(counts, max_points)
    rank = np.empty(n, dtype=np.int64)  # position of each row among its group's rows, in order
    for g in range(len(groups)):
        members = np.nonzero(inverse == g)[0]
        rank[members] = np.arange(members.size)
    return np.sort(order[rank < quota[inverse]])


def heaviest_components(weights: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` largest of ``weights`` (M,), in increasing index order (all of them
    when M <= k; ties go to the lower index)."""
    w = np.asarray(weights, dtype=float).reshape(-1)
    if w.size <= k:
        return np.arange(w.size)
    return np.sort(np.argsort(-w, kind="stable")[:k])
