"""k-means (greedy k-means++ seeding, then Lloyd iterations) in numpy and numba, giving scikit-learn's
``KMeans(n_init=1, algorithm="lloyd")`` result on one thread without importing scikit-learn.

Why: importing ``sklearn.cluster`` costs about 1.3 s of CPU (it imports scipy.stats, which parses
its docstrings at import), half of Example 1's whole run; and each ``KMeans.fit`` spends
milliseconds validating parameters and limiting thread pools, on a 2,500-point fit that takes
less than that. The PGM clusters at every update, so both costs count.

The steps and the random draws are the ones scikit-learn documents for its estimator, in the same
order and with the same numpy operations, so that a fit from the same integer seed returns the
same centres and labels (``tests/clustering/test_lloyd.py`` compares them bit for bit):

1. centre the data on its mean; tolerance = ``tol`` x mean of the coordinate variances;
2. greedy k-means++: the first centre drawn by ``RandomState(seed).choice`` with uniform
   probabilities, each further one the best (lowest potential) of ``2 + int(log k)`` candidates
   drawn in proportion to the squared distance to the nearest centre so far;
3. Lloyd: assign each point to the nearest centre (squared distances as ``|c|^2 - 2 x.c``, ties to
   the lowest index), move each centre to the mean of its points (sums in point order, as one
   thread does); stop when no label changes or the squared centre shifts sum to at most the
   tolerance; if stopped by the tolerance, assign once more to the final centres;
4. add the mean back to the centres.

Each Lloyd pass used to cost about 0.2 ms in numpy calls on Example 1's 2,500-point fits (30% of
the run). The products x.c and |c|^2 are still computed by numpy (BLAS and einsum: these fix the
floating-point sums); the nearest-centre scan, the counts and the per-cluster sums run in one
compiled pass (:func:`_lloyd_pass`, numba, cached), whose additions and comparisons are the ones
the numpy code made, in the same order. The pass also takes the two stop tests (labels unchanged;
squared shifts summed), which cost half of each iteration as numpy calls (session 11). The shifts'
sums run left to right, where numpy's reduction may associate them otherwise: the tolerance test
could then come out differently only for a sum within a rounding of the tolerance itself.

A cluster that empties during the iterations is relocated by scikit-learn's own rule, which this
module does not reproduce: :func:`kmeans_fit` then returns None and the caller uses scikit-learn.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import lazy_njit

from .points_and_labels import Standardizer

__all__ = ["kmeans_fit", "nearest_centres"]


def _sq_distances(a: np.ndarray, b: np.ndarray, b_sq_norms: np.ndarray) -> np.ndarray:
    """Squared distances (len(a), len(b)) by the dot-product expansion, clipped at 0."""
    out = -2 * np.dot(a, b.T)
    out += np.einsum("ij,ij->i", a, a)[:, np.newaxis]
    out += b_sq_norms[np.newaxis, :]
    np.maximum(out, 0, out=out)
    return out


def _seed_centres(x: np.ndarray, k: int, sq_norms: np.ndarray, rs: np.random.RandomState) -> np.ndarray:
    """Greedy k-means++ centres (k, d) of the centred points ``x`` (n, d)."""
    n, d = x.shape
    weights = np.ones(n)
    trials = 2 + int(np.log(k))
    centres = np.empty((k, d))
    centres[0] = x[rs.choice(n, p=weights / weights.sum())]
    closest = _sq_distances(centres[0, np.newaxis], x, sq_norms)
    potential = closest @ weights
    for c in range(1, k):
        targets = rs.uniform(size=trials) * potential
        ids = np.searchsorted(np.cumsum(weights * closest, dtype=np.float64), targets)
        np.minimum(ids, closest.size - 1, out=ids)  # np.clip's upper bound without its checks (30 us)
        dist = _sq_distances(x[ids], x, sq_norms)
        np.minimum(closest, dist, out=dist)
        pots = dist @ weights.reshape(-1, 1)
        best = int(np.argmin(pots))
        potential = pots[best]
        closest = dist[best]
        centres[c] = x[ids[best]]
    return centres


def _products(x: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x.(-2c) (n, k) and |c|^2 (k,): the two terms of the distances |c|^2 - 2 x.c, computed by
    numpy (BLAS and einsum) exactly as before the compiled pass, so the sums are bit for bit the
    ones scikit-learn's Lloyd compares. x.(-2c) is bit for bit -2 (x.c) (scaling by 2 is exact)."""
    return x @ ((-2.0) * centres).T, np.einsum("ij,ij->i", centres, centres)


@lazy_njit(cache=True)
def _lloyd_pass(x, products, c_norms, labels, sums, counts, update, centres, labels_old, stop):
    """One Lloyd pass over the points, compiled: the loops that cost microseconds each in numpy.

    x (n, d) centred points; products (n, k) = x.(-2c); c_norms (k,) = |c|^2. Writes ``labels``
    (n,): the centre with the smallest ``products[i, j] + c_norms[j]``, ties to the lowest index
    (a strict ``<`` scan, as numpy's loop over centres). With ``update``, also writes ``counts``
    (k,) and ``sums`` (k, d) = the new centres: per cluster, the coordinates summed in point order
    (one thread's order, as ``np.bincount``) times the reciprocal of the count, and ``stop`` (2,):
    whether ``labels`` equal ``labels_old`` (1.0 or 0.0) and the sum over clusters of the squared
    shifts from ``centres`` (k, d), each shift sqrt(sum of squared coordinate differences) as
    scikit-learn takes it. Returns the number of clusters left empty (then ``sums`` and ``stop``
    are not meaningful)."""
    n, d = x.shape
    k = c_norms.shape[0]
    for i in range(n):
        best = products[i, 0] + c_norms[0]
        lab = 0
        for j in range(1, k):
            v = products[i, j] + c_norms[j]
            if v < best:
                best = v
                lab = j
        labels[i] = lab
    if not update:
        return 0
    for j in range(k):
        counts[j] = 0
        for a in range(d):
            sums[j, a] = 0.0
    for i in range(n):
        lab = labels[i]
        counts[lab] += 1
        for a in range(d):
            sums[lab, a] += x[i, a]
    empty = 0
    for j in range(k):
        if counts[j] == 0:
            empty += 1
            continue
        inv = 1.0 / np.float64(counts[j])  # as scikit-learn: times the reciprocal
        for a in range(d):
            sums[j, a] *= inv
    same = 1.0
    for i in range(n):
        if labels[i] != labels_old[i]:
            same = 0.0
            break
    total = 0.0
    for j in range(k):
        sq = 0.0
        for a in range(d):
            diff = sums[j, a] - centres[j, a]
            sq += diff * diff
        shift = np.sqrt(sq)
        total += shift * shift
    stop[0] = same
    stop[1] = total
    return empty


_ROWS_AT_ONCE = 65_536
"""Points labelled per block by :func:`nearest_centres` (its temporaries: 2 z and the (n, k)
products, which at the PGM's 4 x 1,000,000 reacquisition particles were 200 MB and more)."""


def nearest_centres(z: np.ndarray | Standardizer, centres: np.ndarray) -> np.ndarray:
    """Index (n,) of the nearest of ``centres`` (k, d) for each point of ``z`` (n, d), first on
    ties: numpy's ``argmin(|z|^2 - (2 z).c + |c|^2, axis=1)`` (the products by numpy, the sums and
    the scan compiled, in the same order), for labelling every particle after a subsampled fit.
    ``z`` may be a :class:`Standardizer`, whose rows are standardised block by block."""
    if not isinstance(z, Standardizer):
        z = np.asarray(z, dtype=np.float64)
    labels = np.empty(len(z), dtype=np.intp)
    c_norms = np.einsum("ij,ij->i", centres, centres)
    for a in range(0, len(z), _ROWS_AT_ONCE):  # rows in blocks: each row's numbers are its own
        zb = z[a:a + _ROWS_AT_ONCE] if isinstance(z, np.ndarray) else z.rows(a, a + _ROWS_AT_ONCE)
        products = np.ascontiguousarray((2.0 * zb) @ centres.T)
        _nearest(np.einsum("ij,ij->i", zb, zb), products, c_norms, labels[a:a + _ROWS_AT_ONCE])
    return labels


@lazy_njit(cache=True)
def _nearest(z_norms, products, c_norms, labels):
    """labels[i] = first j minimising (z_norms[i] - products[i, j]) + c_norms[j]."""
    n, k = products.shape
    for i in range(n):
        best = (z_norms[i] - products[i, 0]) + c_norms[0]
        lab = 0
        for j in range(1, k):
            v = (z_norms[i] - products[i, j]) + c_norms[j]
            if v < best:
                best = v
                lab = j
        labels[i] = lab


def kmeans_fit(x: np.ndarray, k: int, seed: int, max_iter: int = 300,
               tol: float = 1e-4) -> tuple[np.ndarray, np.ndarray] | None:
    """Centres (k, d) and labels (n,) of k-means on points ``x`` (n, d), n >= k, from ``seed``
    (an int, as scikit-learn's ``random_state``); None when a cluster empties (see the module)."""
    x = np.array(x, dtype=np.float64, order="C")
    n, d = x.shape
    tolerance = np.mean(np.var(x, axis=0)) * tol if tol else 0.0
    mean = x.mean(axis=0)
    x -= mean
    rs = np.random.RandomState(seed)
    centres = _seed_centres(x, k, np.einsum("ij,ij->i", x, x), rs)
    labels_old = np.full(n, -1, dtype=np.intp)
    labels = np.empty(n, dtype=np.intp)
    counts = np.empty(k, dtype=np.intp)
    stop = np.empty(2)
    strict = False
    for _ in range(max_iter):
        new = np.empty((k, d))
        if _lloyd_pass(x, *_products(x, centres), labels, new, counts, True, centres, labels_old, stop):
            return None
        centres = new
        if stop[0]:  # no label changed
            strict = True
            break
        if stop[1] <= tolerance:  # the centres moved by at most the tolerance
            break
        labels_old, labels = labels, labels_old
    if not strict:
        _lloyd_pass(x, *_products(x, centres), labels, np.empty((k, d)), counts, False, centres, labels_old, stop)
    centres += mean
    return centres, labels
