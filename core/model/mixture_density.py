"""Compiled densities of Gaussian mixtures: the log density of every point under every component,
and the log-sum-exp over components, on disjoint ranges of rows (on the worker threads for many
points). Used by :class:`cistrack.model.belief.GaussianMixture`.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import lazy_njit
from cistrack.threads import run_chunks

__all__: list[str] = []

_BLOCK = 256  # points per block of the compiled density: the block's work arrays stay in L1


@lazy_njit(cache=True, nogil=True)
def _whitened_logpdf(i0, i1, x, means, linv, const, logw, out):
    """out[n, m] = const[m] + logw[m] - |linv[m] (x[n] - means[m])|^2 / 2 (linv lower triangular),
    for the rows n in [i0, i1) (several threads take disjoint ranges).

    x (N, d), means (M, d), linv (M, d, d), const and logw (M,), out (N, M). Points go in blocks
    of ``_BLOCK``; within a block each operation runs over the points in an inner loop, which
    the compiler turns into SIMD instructions. Every point sees the same operations in the same
    order as a plain per-point loop (``s = 0; s += linv[a, b] diff[b]`` for b = 0..a, then
    ``maha += s^2`` for a = 0..d-1), so the numbers do not depend on the blocking or the ranges.
    """
    d = x.shape[1]
    n_comp = means.shape[0]
    diff = np.empty((d, _BLOCK))
    s = np.empty(_BLOCK)
    maha = np.empty(_BLOCK)
    for start in range(i0, i1, _BLOCK):
        nb = min(_BLOCK, i1 - start)
        for m in range(n_comp):
            for b in range(d):
                mb = means[m, b]
                for i in range(nb):
                    diff[b, i] = x[start + i, b] - mb
            for i in range(nb):
                maha[i] = 0.0
            for a in range(d):
                for i in range(nb):
                    s[i] = 0.0
                for b in range(a + 1):
                    lab = linv[m, a, b]
                    for i in range(nb):
                        s[i] += lab * diff[b, i]
                for i in range(nb):
                    maha[i] += s[i] * s[i]
            c = const[m] + logw[m]
            for i in range(nb):
                out[start + i, m] = c - 0.5 * maha[i]


@lazy_njit(cache=True, nogil=True)
def _whitened_6(i0, i1, x, means, linv, const, logw, out):
    """:func:`_whitened_logpdf` for d = 6 (the state; :func:`whitened_kernel` picks it), bit for
    bit: per point the same subtractions, products and sums in the same order (``s = 0; s +=
    linv[a, b] diff[b]`` for b = 0..a, then ``maha += s^2``), held in registers instead of block
    arrays, so that the inner loop over a block's points loads each coordinate once (the general
    loop stored and reloaded ``s`` 21 times). Same arguments and shapes."""
    n_comp = means.shape[0]
    xt = np.empty((6, _BLOCK))
    row = np.empty(_BLOCK)
    for start in range(i0, i1, _BLOCK):
        nb = min(_BLOCK, i1 - start)
        for b in range(6):
            for i in range(nb):
                xt[b, i] = x[start + i, b]
        for m in range(n_comp):
            m0, m1, m2, m3, m4, m5 = means[m, 0], means[m, 1], means[m, 2], means[m, 3], means[m, 4], means[m, 5]
            L = linv[m]
            l00 = L[0, 0]
            l10, l11 = L[1, 0], L[1, 1]
            l20, l21, l22 = L[2, 0], L[2, 1], L[2, 2]
            l30, l31, l32, l33 = L[3, 0], L[3, 1], L[3, 2], L[3, 3]
            l40, l41, l42, l43, l44 = L[4, 0], L[4, 1], L[4, 2], L[4, 3], L[4, 4]
            l50, l51, l52, l53, l54, l55 = L[5, 0], L[5, 1], L[5, 2], L[5, 3], L[5, 4], L[5, 5]
            c = const[m] + logw[m]
            for i in range(nb):
                d0 = xt[0, i] - m0
                d1 = xt[1, i] - m1
                d2 = xt[2, i] - m2
                d3 = xt[3, i] - m3
                d4 = xt[4, i] - m4
                d5 = xt[5, i] - m5
                s0 = 0.0 + l00 * d0
                s1 = (0.0 + l10 * d0) + l11 * d1
                s2 = ((0.0 + l20 * d0) + l21 * d1) + l22 * d2
                s3 = (((0.0 + l30 * d0) + l31 * d1) + l32 * d2) + l33 * d3
                s4 = ((((0.0 + l40 * d0) + l41 * d1) + l42 * d2) + l43 * d3) + l44 * d4
                s5 = (((((0.0 + l50 * d0) + l51 * d1) + l52 * d2) + l53 * d3) + l54 * d4) + l55 * d5
                maha = (((((0.0 + s0 * s0) + s1 * s1) + s2 * s2) + s3 * s3) + s4 * s4) + s5 * s5
                row[i] = c - 0.5 * maha
            for i in range(nb):
                out[start + i, m] = row[i]


def whitened_kernel(d: int):
    """The compiled density kernel for points of dimension ``d``: :func:`_whitened_6` for 6,
    else :func:`_whitened_logpdf` (same numbers; the arguments of either)."""
    return _whitened_6 if d == 6 else _whitened_logpdf


@lazy_njit(cache=True, nogil=True)
def _row_logsumexp(i0, i1, a, out):
    """out[n] = log sum_m exp(a[n, m]) for the rows n in [i0, i1) of a (N, M), -inf rows giving
    -inf, NaN propagating."""
    n_comp = a.shape[1]
    for n in range(i0, i1):
        mx = -np.inf
        nan = False
        for m in range(n_comp):
            v = a[n, m]
            if v != v:
                nan = True
            elif v > mx:
                mx = v
        if nan:
            out[n] = np.nan
            continue
        if not np.isfinite(mx):
            mx = 0.0
        s = 0.0
        for m in range(n_comp):  # exp(0) = 1 and exp(< -750) = 0 exactly: those terms need no call
            v = a[n, m] - mx
            if v == 0.0:
                s += 1.0
            elif v >= -750.0:
                s += np.exp(v)
        out[n] = mx + np.log(s)


_THREADED_ROWS = 16_384
"""Rows from which the densities run on the worker threads (:mod:`cistrack.threads`); below it
handing out the work costs about what it saves (6 components, 2 threads, the 2-core development
machine, medians of 200, threaded against one thread: 0.42 against 0.28 ms at 5,000 rows, 0.56
against 0.59 at 10,000, 0.89 against 1.28 at 20,000, 1.49 against 2.50 at 40,000)."""


def _by_rows(kernel, n: int, args: tuple) -> None:
    """``kernel(i0, i1, *args)`` over the rows 0..n, on the worker threads when there are many."""
    if n >= _THREADED_ROWS:
        run_chunks(kernel, n, args, chunks_per_worker=1)
    else:
        kernel(0, n, *args)
