"""k-means compiled with numba: greedy k-means++ seeding and Lloyd iterations (the optional
"kmeans-numba" start of the numba EM engine of GMMClusterer).

Arrays: points ``x`` (n, d) float64, held transposed (d, n) inside the kernels; centres (k, d);
labels (n,) int64.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["kmeans_labels"]


def _t(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64).T)


@nb.njit(cache=True)
def _sq_dist_to(xt, centre, out):
    d, n = xt.shape
    for i in range(n):
        out[i] = 0.0
    for a in range(d):
        xa = xt[a]
        ca = centre[a]
        for i in range(n):
            t = xa[i] - ca
            out[i] += t * t


@nb.njit(cache=True)
def _kmeans_pp(xt, k, first, uniforms):
    """Greedy k-means++ centres (k, d): each new centre is the best (lowest total squared
    distance) of ``uniforms.shape[1]`` candidates drawn proportionally to the squared distance."""
    d, n = xt.shape
    trials = uniforms.shape[1]
    centres = np.empty((k, d))
    centres[0] = xt[:, first]
    closest = np.empty(n)
    _sq_dist_to(xt, centres[0], closest)
    cand = np.empty(n)
    best_d = np.empty(n)
    cum = np.empty(n)
    for c in range(1, k):
        s = 0.0
        for i in range(n):
            s += closest[i]
            cum[i] = s
        best_pot = np.inf
        best_id = 0
        for t in range(trials):
            idx = np.searchsorted(cum, uniforms[c - 1, t] * s)
            if idx >= n:
                idx = n - 1
            _sq_dist_to(xt, xt[:, idx].copy(), cand)
            pot = 0.0
            for i in range(n):
                if cand[i] < closest[i]:
                    pot += cand[i]
                else:
                    pot += closest[i]
            if pot < best_pot:
                best_pot = pot
                best_id = idx
        centres[c] = xt[:, best_id]
        _sq_dist_to(xt, centres[c], best_d)
        for i in range(n):
            if best_d[i] < closest[i]:
                closest[i] = best_d[i]
    return centres


@nb.njit(cache=True)
def _assign(xt, centres, dq, labels, dist):
    """Nearest centre of each point of ``xt`` (d, n) into ``labels``/``dist``; number changed."""
    k = centres.shape[0]
    n = xt.shape[1]
    for c in range(k):
        _sq_dist_to(xt, centres[c], dq[c])
    changed = 0
    for i in range(n):
        dist[i] = dq[0, i]
    b = np.zeros(n, dtype=np.intp)
    for c in range(1, k):
        dc = dq[c]
        for i in range(n):
            if dc[i] < dist[i]:
                dist[i] = dc[i]
                b[i] = c
    for i in range(n):
        if labels[i] != b[i]:
            changed += 1
            labels[i] = b[i]
    return changed


@nb.njit(cache=True)
def _lloyd(xt, centres, max_iter, tol):
    """Lloyd iterations on points ``xt`` (d, n) from ``centres`` (k, d), in place; labels (n,).
    Stops when no label changes or the total squared centre shift is <= ``tol`` (then points are
    re-assigned to the final centres); an empty cluster is re-seeded at the point farthest from
    its centre."""
    d, n = xt.shape
    k = centres.shape[0]
    labels = np.full(n, -1, dtype=np.intp)
    dist = np.empty(n)
    dq = np.empty((k, n))
    new = np.empty((k, d))
    count = np.empty(k)
    for it in range(max_iter):
        if _assign(xt, centres, dq, labels, dist) == 0:
            break
        new[:] = 0.0
        count[:] = 0.0
        for i in range(n):
            c = labels[i]
            count[c] += 1.0
            for a in range(d):
                new[c, a] += xt[a, i]
        for c in range(k):
            if count[c] == 0.0:
                far = np.argmax(dist)
                dist[far] = -1.0
                for a in range(d):
                    new[c, a] = xt[a, far]
                count[c] = 1.0
                continue
            for a in range(d):
                new[c, a] /= count[c]
        shift = 0.0
        for c in range(k):
            for a in range(d):
                t = new[c, a] - centres[c, a]
                shift += t * t
                centres[c, a] = new[c, a]
        if shift <= tol:
            _assign(xt, centres, dq, labels, dist)
            break
    return labels


def kmeans_labels(x: np.ndarray, k: int, rng: np.random.Generator, max_iter: int = 300,
                  tol: float = 1e-4) -> np.ndarray:
    """k-means labels (n,) of points ``x`` (n, d): greedy k-means++ (2 + ln k candidates per
    centre, as scikit-learn) then Lloyd iterations until no label changes or the total squared
    centre shift is <= ``tol`` times the mean coordinate variance. Randomness from ``rng``."""
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[0]
    trials = 2 + int(np.log(k))
    first = int(rng.integers(n))
    uniforms = rng.random((max(k - 1, 1), trials))
    xt = _t(x)
    centres = _kmeans_pp(xt, k, first, uniforms)
    return _lloyd(xt, centres, int(max_iter), float(tol * np.mean(np.var(x, axis=0))))
