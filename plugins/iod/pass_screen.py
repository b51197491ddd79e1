"""Gross outliers in the first pass, found before the IOD fits through them.

The kinematic fit (:mod:`.kinematic_fit`) and Gauss's method fit polynomials through the first
pass's measurements: one observation a degree off (a wrong object, a mistyped time) bends every
sample, and the filter never recovers. Over a pass of a few hours, the line of sight in the
synodic frame is a smooth curve: :func:`screen_pass` fits a polynomial in time to its three
components with each measurement left out in turn, and takes out the measurement whose leaving
out fits the rest best, when the rest then fit within :data:`CONSISTENT_RMS` of their noise and
that measurement lies more than :data:`MIN_OFFSET_SIGMA` of its noise, :data:`MIN_OFFSET_RMS`
times the rest's scatter and :data:`MIN_OFFSET_LOO` times the farthest any of the rest lies off
a curve fitted without it. At most :data:`MAX_SCREENED` measurements are taken out,
and never so many that the pass becomes too short. Data that only scatter (noise, or a long pass
the polynomial follows only roughly) take nothing out: the test is against the others' own
scatter, and only a measurement hundreds of sigma off passes it.

Cost: the polynomial is fitted once to the whole pass, and the fit without any one or two
measurements follows from that fit in closed form (the least-squares deletion formulas), so that
a pass of K measurements costs O(K) and a fixed number of refits, whatever K. Pairs are tried
among the :data:`MAX_PAIR_CANDIDATES` measurements whose leaving out alone fits the rest best
(all pairs of a pass with no more measurements than that).
"""
from __future__ import annotations

import numpy as np

__all__ = ["screen_pass", "CONSISTENT_RMS", "MIN_OFFSET_SIGMA", "MIN_OFFSET_RMS", "MIN_OFFSET_LOO", "MAX_SCREENED",
           "MAX_PAIR_CANDIDATES"]

CONSISTENT_RMS = 30.0
"""The rest must fit their curve within this many sigma, root mean square (a long pass with
precise data is followed by an order-4 polynomial only to some arcseconds: 6.6 sigma over a
14-measurement pass at 1 arcsec)."""
MIN_OFFSET_SIGMA = 500.0
"""A measurement taken out lies at least this many of its sigma off the rest's curve (750" at 1.5";
clean passes of nine scenarios, 100 seeds each, came to at most 82 sigma, at a pass's end)."""
MIN_OFFSET_RMS = 20.0
"""... at least this many times the rest's root-mean-square scatter about it ..."""
MIN_OFFSET_LOO = 10.0
"""... and at least this many times the largest offset of any of the rest left out in turn (how
far the curve misses a measurement it was not fitted to, extrapolation at the ends included)."""
MAX_SCREENED = 2
"""At most this many measurements are taken out of a pass (no more than 2: :func:`_inverse`)."""
MAX_PAIR_CANDIDATES = 64
"""Pairs are searched among this many measurements, those whose leaving out alone fits the rest
best (a pair of gross outliers is among them: each one's leaving out takes its own offset out)."""


def _scaled_basis(t: np.ndarray, keep: np.ndarray, order: int) -> np.ndarray:
    """Vandermonde matrix (K, order + 1) in time centred and scaled on the kept measurements."""
    tc = t - t[keep].mean()
    scale = max(float(np.abs(tc[keep]).max()), 1e-12)
    return np.vander(tc / scale, order + 1)


def _fit_residuals(t: np.ndarray, u: np.ndarray, keep: np.ndarray, order: int) -> np.ndarray:
    """Angles (K,) rad between each line of sight and the polynomial fitted to the kept ones."""
    basis = _scaled_basis(t, keep, order)
    coef, *_ = np.linalg.lstsq(basis[keep], u[keep], rcond=None)
    d = u - basis @ coef
    return np.linalg.norm(d, axis=1)


class _Deletions:
    """The polynomial fitted once to all K measurements, and what leaving some out does to it.

    ``q`` (K, P) orthonormal basis of the polynomials at the times (P = order + 1); ``e`` (K, 3)
    residuals of the fit to all; ``w`` (K,) weights 1/sigma^2 rad^-2 of the root-mean-square test.
    """

    def __init__(self, t: np.ndarray, u: np.ndarray, s: np.ndarray, order: int):
        self.q, _ = np.linalg.qr(_scaled_basis(t, np.ones(t.shape[0], dtype=bool), order))
        self.e = u - self.q @ (self.q.T @ u)
        self.w = 1.0 / s ** 2
        self.total = float(np.sum(self.w * np.sum(self.e ** 2, axis=1)))
        self.pw = (self.w[:, None] * self.e).T @ self.q      # (3, P): sum_k w_k e_k q_k^T
        self.mw = self.q.T @ (self.w[:, None] * self.q)      # (P, P): sum_k w_k q_k q_k^T

    def rest_rms(self, sets: np.ndarray) -> np.ndarray:
        """Weighted root-mean-square residual (S,) of the rest about the curve fitted without each
        set of ``sets`` (S, m) indices; inf where it cannot be told.

        Without the set D, the rest's residuals are e + H[:, D] c with c = (I - H[D, D])^-1 e[D]
        (H = q q^T), and c is the left-out measurements' own offset from that curve.
        """
        n, m = self.q.shape[0], sets.shape[1]
        qs = self.q[sets]                                            # (S, m, P)
        hdd = np.einsum("smp,snp->smn", qs, qs)
        with np.errstate(all="ignore"):
            c = np.einsum("smn,snc->smc", _inverse(np.eye(m) - hdd), self.e[sets])   # (S, m, 3)
            cross = 2.0 * np.einsum("smp,cp,smc->s", qs, self.pw, c)
            g = np.einsum("smp,pr,snr->smn", qs, self.mw, qs)
            quad = np.einsum("smn,smc,snc->s", g, c, c)
            left = np.einsum("sm,smc->s", self.w[sets], c ** 2)
            rms = np.sqrt(np.maximum(self.total + cross + quad - left, 0.0) / (n - m))
        return np.where(np.isfinite(rms), rms, np.inf)


def _inverse(a: np.ndarray) -> np.ndarray:
    """Inverses (S, m, m) of 1 x 1 or 2 x 2 matrices ``a`` (S, m, m); inf or nan where singular."""
    if a.shape[1] == 1:
        return 1.0 / a
    det = (a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0])[:, None, None]
    adj = np.stack([np.stack([a[:, 1, 1], -a[:, 0, 1]], axis=1), np.stack([-a[:, 1, 0], a[:, 0, 0]], axis=1)], axis=1)
    return adj / det


def _largest_loo(t: np.ndarray, u: np.ndarray, keep: np.ndarray, order: int) -> float:
    """Largest angle rad by which a curve fitted to the kept measurements without one of them
    misses that one (|e_j| / (1 - h_jj) of the fit to the kept ones)."""
    q, _ = np.linalg.qr(_scaled_basis(t[keep], np.ones(int(keep.sum()), dtype=bool), order))
    e = u[keep] - q @ (q.T @ u[keep])
    with np.errstate(all="ignore"):
        loo = np.linalg.norm(e, axis=1) / (1.0 - np.sum(q ** 2, axis=1))
    return float(np.max(np.where(np.isfinite(loo), loo, np.inf)))


def _candidate_sets(single: np.ndarray, m: int) -> np.ndarray:
    """Index sets (S, m) to try leaving out, in lexicographic order: every measurement for m = 1;
    pairs of the :data:`MAX_PAIR_CANDIDATES` best single removals (``single`` (K,) their rest's
    rms) for m = 2."""
    n = single.shape[0]
    if m == 1:
        return np.arange(n)[:, None]
    k = min(n, MAX_PAIR_CANDIDATES)
    cand = np.sort(np.argsort(single, kind="stable")[:k])
    i, j = np.triu_indices(k, 1)
    return np.stack([cand[i], cand[j]], axis=1)


def screen_pass(times: np.ndarray, los: np.ndarray, sigma: np.ndarray, order: int, need: int) -> list[tuple[int, float]]:
    """Measurements of a pass to leave out: (index, offset rad off the others' curve), by index
    (see the module docstring). One measurement is tried first, and two only when leaving out one
    does not make the rest consistent (the pair search is not run on a clean pass): the
    measurements whose leaving out fits the rest best are left out when the rest are consistent
    and each of them lies far enough off the rest's curve; else nothing is.

    times (K,) TU; los (K, 3) unit lines of sight (one frame for all, e.g. synodic); sigma (K,)
    rad, each measurement's angular noise on the sky; order: the polynomial's order; need: the
    fewest measurements the pass must keep. O(K) in time and memory.
    """
    t = np.asarray(times, dtype=float)
    u = np.asarray(los, dtype=float)
    s = np.asarray(sigma, dtype=float)
    n, p = t.shape[0], int(order)
    if n - 1 < max(need, p + 3):
        return []
    fit = _Deletions(t, u, s, p)
    single = fit.rest_rms(np.arange(n)[:, None])
    for m in range(1, MAX_SCREENED + 1):
        if n - m < max(need, p + 3):
            break
        sets = _candidate_sets(single, m)
        rms = single if m == 1 else fit.rest_rms(sets)
        if not np.isfinite(rms.min()):
            continue
        found = _judged(t, u, s, p, [int(i) for i in sets[int(np.argmin(rms))]])
        if found is not None:
            return found
    return []


def _judged(t: np.ndarray, u: np.ndarray, s: np.ndarray, order: int, best: list[int]) -> list[tuple[int, float]] | None:
    """The verdict on leaving out ``best`` (the set whose leaving out fits the rest best), from a
    fit to the rest: None when the rest are not consistent (try one more), [] when something
    does not lie far enough off, else the measurements with their offsets (rad)."""
    n = t.shape[0]
    keep = np.ones(n, dtype=bool)
    keep[best] = False
    res = _fit_residuals(t, u, keep, order)
    if not float(np.sqrt(np.mean((res[keep] / s[keep]) ** 2))) <= CONSISTENT_RMS:
        return None
    spread = float(np.sqrt(np.mean(res[keep] ** 2)))
    if not all(res[i] >= MIN_OFFSET_SIGMA * s[i] and res[i] >= MIN_OFFSET_RMS * spread for i in best):
        return []  # the rest fit their curve and nothing lies far off it: a clean pass
    loo = _largest_loo(t, u, keep, order)
    return [(i, float(res[i])) for i in best] if all(res[i] >= MIN_OFFSET_LOO * loo for i in best) else []
