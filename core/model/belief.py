"""Belief types shared by every filter, IOD method and metric.

States are nondimensional synodic, shape ``(N, d)`` with d = 6 for orbits
(x, y, z in LU; vx, vy, vz in VU). Times are TU since the scenario epoch.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from cistrack.numerics.special_functions import logsumexp
from cistrack.model.mixture_density import _by_rows, _row_logsumexp, _whitened_logpdf, whitened_kernel  # noqa: F401

__all__ = ["ParticleCloud", "GaussianMixture", "Belief", "sample_covariance", "regularize_covariance", "read_only_view"]

_LOG_2PI = float(np.log(2.0 * np.pi))


def sample_covariance(x: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Unbiased (weighted) sample covariance of rows of ``x`` (N, d) -> (d, d)."""
    x = np.asarray(x, dtype=float)
    if weights is None:
        if x.shape[0] < 2:
            return np.zeros((x.shape[1], x.shape[1]))
        return np.cov(x, rowvar=False).reshape(x.shape[1], x.shape[1])
    w = np.asarray(weights, dtype=float)
    w = w / w.sum()
    mean = w @ x
    d = x - mean
    denom = 1.0 - np.sum(w * w)
    c = (d * w[:, None]).T @ d
    return c / denom if denom > 0 else c


def regularize_covariance(p: np.ndarray, rel: float = 1e-12, each: bool = False) -> np.ndarray:
    """Symmetrise ``p`` (..., d, d) and lift eigenvalues below ``rel``·max(diag) to that floor.

    Keeps a covariance positive definite after a Joseph-less Kalman update or a degenerate
    cluster without changing well-conditioned matrices. A stack is rebuilt from its eigenvectors
    as a whole when any matrix needs lifting; with ``each`` (p (M, d, d)) only the matrices that
    need it are, so that each matrix comes out as it would alone.
    """
    p = 0.5 * (p + np.swapaxes(p, -1, -2))
    w, v = np.linalg.eigh(p)
    scale = np.max(np.abs(np.diagonal(p, axis1=-2, axis2=-1)), axis=-1, keepdims=True)
    floor = np.maximum(rel * scale, np.finfo(float).tiny)
    low = w < floor
    if not np.any(low):
        return p
    w = np.maximum(w, floor)
    if each and p.ndim == 3:
        sel = np.any(low, axis=-1)
        p[sel] = (v[sel] * w[sel][:, None, :]) @ np.swapaxes(v[sel], -1, -2)
        return p
    return (v * w[..., None, :]) @ np.swapaxes(v, -1, -2)


def read_only_view(a):
    """``a`` itself unless it is a writeable ndarray, else a view of it that refuses writes (no
    copy: the data stays shared, its owner can still change it)."""
    if not isinstance(a, np.ndarray) or not a.flags.writeable:
        return a
    v = a.view()
    v.flags.writeable = False
    return v


def _is_finite_number(v) -> bool:
    if isinstance(v, (bool, str, bytes)):
        return False
    try:
        return bool(np.isfinite(float(v)))
    except (TypeError, ValueError):
        return False


@dataclass
class ParticleCloud:
    """Samples of a belief.

    Attributes
    ----------
    states : (N, d) float
        Particles, nondimensional synodic.
    epoch : float
        Time of the states, TU since the scenario epoch.
    weights : (N,) float or None
        Normalised importance weights; None means equal weights.
    labels : (N,) int or None
        Component label of each particle, when a clusterer assigned one.
    meta : dict
        Free-form provenance of the cloud (e.g. an IOD method's draws, survivors and pruning
        counts); never used in computations.
    """

    states: np.ndarray
    epoch: float
    weights: np.ndarray | None = None
    labels: np.ndarray | None = None
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        self.states = np.atleast_2d(np.asarray(self.states, dtype=float))
        n = self.states.shape[0]
        if not _is_finite_number(self.epoch):
            raise ValueError(f"ParticleCloud: epoch must be a finite time in TU, got {self.epoch!r}")
        if self.weights is not None:
            w = np.asarray(self.weights, dtype=float)
            if w.shape != (n,):
                raise ValueError(f"weights shape {w.shape} does not match {n} particles")
            if not (np.all(np.isfinite(w)) and np.all(w >= 0.0) and w.sum() > 0.0):
                raise ValueError("ParticleCloud: weights must be finite, non-negative and not all zero")
            self.weights = w / w.sum()
        if self.labels is not None:
            lab = np.asarray(self.labels)
            if lab.shape != (n,) or lab.dtype.kind not in "iu" or (n and lab.min() < 0):
                raise ValueError(f"ParticleCloud: labels must be {n} whole numbers >= 0, one per particle")

    def __len__(self) -> int:
        return self.states.shape[0]

    @property
    def mean(self) -> np.ndarray:
        """Weighted mean, (d,)."""
        if self.weights is None:
            return self.states.mean(axis=0)
        return self.weights @ self.states

    @property
    def covariance(self) -> np.ndarray:
        """Weighted sample covariance, (d, d)."""
        return sample_covariance(self.states, self.weights)

    def moment_match(self) -> "GaussianMixture":
        """Single-component mixture with the cloud's mean and covariance."""
        return GaussianMixture(np.ones(1), self.mean[None], self.covariance[None])

    def read_only(self) -> "ParticleCloud":
        """This cloud with read-only views of its arrays (no copy, no checks run again)."""
        out = copy.copy(self)
        out.states, out.weights, out.labels = (read_only_view(a) for a in (self.states, self.weights, self.labels))
        return out


_SAMPLE_CHUNK = 65_536
"""Rows of standard normals drawn at once by :meth:`GaussianMixture.sample` (3 MiB at d = 6)."""


@dataclass
class GaussianMixture:
    """A Gaussian mixture density.

    Attributes
    ----------
    weights : (M,) float, normalised to sum 1
    means : (M, d) float
    covariances : (M, d, d) float, symmetric positive definite
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    _chol: np.ndarray | None = field(default=None, repr=False, compare=False)
    _whiten: tuple | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.weights = np.atleast_1d(np.asarray(self.weights, dtype=float))
        self.means = np.atleast_2d(np.asarray(self.means, dtype=float))
        self.covariances = np.asarray(self.covariances, dtype=float)
        if self.covariances.ndim == 2:
            self.covariances = self.covariances[None]
        m, d = self.means.shape
        if self.weights.shape != (m,) or self.covariances.shape != (m, d, d):
            raise ValueError(
                f"inconsistent mixture shapes: weights {self.weights.shape}, means {self.means.shape}, "
                f"covariances {self.covariances.shape}")
        if not (np.all(np.isfinite(self.weights)) and np.all(self.weights >= 0) and self.weights.sum() > 0):
            raise ValueError("mixture weights must be finite, non-negative and not all zero")
        self.weights = self.weights / self.weights.sum()

    @property
    def n_components(self) -> int:
        return self.means.shape[0]

    @property
    def dim(self) -> int:
        return self.means.shape[1]

    def cholesky(self) -> np.ndarray:
        """Lower Cholesky factors (M, d, d), regularising a covariance that is not PD."""
        if self._chol is None:
            try:
                self._chol = np.linalg.cholesky(self.covariances)
            except np.linalg.LinAlgError:
                self.covariances = regularize_covariance(self.covariances, 1e-10)
                self._chol = np.linalg.cholesky(self.covariances)
        return self._chol

    def _whitening(self) -> tuple[np.ndarray, np.ndarray]:
        """Inverse Cholesky factors (M, d, d) and log normalising constants (M,), kept with the
        Cholesky factors they came from (a run's metrics evaluate each belief's density twice:
        at its samples and at the truth)."""
        chol = self.cholesky()
        if self._whiten is not None and self._whiten[0] is chol:
            return self._whiten[1], self._whiten[2]
        linv = np.ascontiguousarray(np.linalg.inv(chol))  # one batched call
        logdet = 2.0 * np.sum(np.log(np.diagonal(chol, axis1=-2, axis2=-1)), axis=-1)
        const = np.ascontiguousarray(-0.5 * (logdet + self.dim * _LOG_2PI))
        self._whiten = (chol, linv, const)
        return linv, const

    def _logpdf_table(self, x: np.ndarray, log_weights: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(np.atleast_2d(np.asarray(x, dtype=float)))
        if x.ndim != 2 or x.shape[1] != self.dim:
            raise ValueError(f"points must have shape (N, {self.dim}), got {x.shape}")
        linv, const = self._whitening()
        out = np.empty((x.shape[0], self.n_components))
        _by_rows(whitened_kernel(self.dim), x.shape[0], (x, np.ascontiguousarray(self.means), linv, const,
                                                np.ascontiguousarray(log_weights, dtype=float), out))
        return out

    def component_logpdf(self, x: np.ndarray) -> np.ndarray:
        """log N(x; mu_i, P_i) for every point and component: x (N, d) -> (N, M)."""
        return self._logpdf_table(x, np.zeros(self.n_components))

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        """Log density of points ``x`` (N, d) -> (N,). Rows in blocks of ``_SAMPLE_CHUNK`` (each
        row's density is its own): the (N, M) table of component densities is a block's."""
        x = np.asarray(x, dtype=float)
        if x.ndim == 2 and x.shape[0] > _SAMPLE_CHUNK:
            out = np.empty(x.shape[0])
            for lo in range(0, x.shape[0], _SAMPLE_CHUNK):
                out[lo:lo + _SAMPLE_CHUNK] = self.logpdf(x[lo:lo + _SAMPLE_CHUNK])
            return out
        with np.errstate(divide="ignore"):
            logw = np.log(self.weights)
        a = self._logpdf_table(x, logw)
        if a.shape[1] == 1:
            return a[:, 0]
        out = np.empty(a.shape[0])
        _by_rows(_row_logsumexp, a.shape[0], (a, out))
        return out

    def responsibilities(self, x: np.ndarray) -> np.ndarray:
        """Posterior component probabilities of each point, (N, M)."""
        with np.errstate(divide="ignore"):
            a = self.component_logpdf(x) + np.log(self.weights)
        return np.exp(a - logsumexp(a, axis=1, keepdims=True))

    def sample(self, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Draw ``n`` points. Returns (samples (n, d), component labels (n,))."""
        labels = rng.choice(self.n_components, size=n, p=self.weights)
        labels.sort()
        edges = np.searchsorted(labels, np.arange(self.n_components + 1))
        return self.draw_blocks(edges, rng), labels

    def draw_blocks(self, edges: np.ndarray, rng: np.random.Generator, chunk: int = _SAMPLE_CHUNK) -> np.ndarray:
        """Draws (edges[-1], d) whose rows edges[i]:edges[i+1] come from component i (``edges``
        (M + 1,) nondecreasing from 0). The standard normals are drawn block by block, ``chunk``
        rows at a time, in row order: the same numbers as one (n, d) draw (numpy's generator
        fills arrays one value after the other), without holding all of them (the peak memory of
        a run is here, with reacquire_factor x n_particles draws)."""
        chol = self.cholesky()
        out = np.empty((int(edges[-1]), self.dim))
        for i in range(self.n_components):
            for a in range(int(edges[i]), int(edges[i + 1]), chunk):
                b = min(a + chunk, int(edges[i + 1]))
                np.matmul(rng.standard_normal((b - a, self.dim)), chol[i].T, out=out[a:b])
                out[a:b] += self.means[i]
        return out

    @property
    def mean(self) -> np.ndarray:
        """Mixture mean, (d,)."""
        return self.weights @ self.means

    @property
    def covariance(self) -> np.ndarray:
        """Mixture covariance (law of total covariance), (d, d)."""
        mu = self.mean
        diff = self.means - mu
        return (np.einsum("m,mij->ij", self.weights, self.covariances)
                + np.einsum("m,mi,mj->ij", self.weights, diff, diff))

    def read_only(self) -> "GaussianMixture":
        """This mixture with read-only views of its weights, means and covariances (no copy, no
        checks run again)."""
        out = copy.copy(self)
        out.weights, out.means, out.covariances = (read_only_view(a) for a in (self.weights, self.means,
                                                                               self.covariances))
        return out

    def moment_match(self) -> "GaussianMixture":
        """Single Gaussian with the mixture's mean and covariance."""
        return GaussianMixture(np.ones(1), self.mean[None], self.covariance[None])

    def marginal(self, idx) -> "GaussianMixture":
        """Marginal over coordinates ``idx`` (e.g. slice(0, 3) for position)."""
        idx = np.arange(self.dim)[idx]
        return GaussianMixture(self.weights, self.means[:, idx], self.covariances[:, idx][:, :, idx])


@dataclass
class Belief:
    """What every filter exposes: its density as a mixture plus samples of it.

    Attributes
    ----------
    epoch : float
        TU since the scenario epoch.
    mixture : GaussianMixture
        The filter's density (a Kalman filter's is a mixture of one).
    samples : ParticleCloud
        Particles of the belief (the filter's own particles, or draws from the mixture).
    """

    epoch: float
    mixture: GaussianMixture
    samples: ParticleCloud

    def read_only(self) -> "Belief":
        """This belief with read-only views of its arrays (what observers are handed: writing into
        it raises ValueError instead of changing the filter's state). Costs no copy of the data."""
        out = copy.copy(self)
        out.mixture, out.samples = _read_only_part(self.mixture), _read_only_part(self.samples)
        return out


def _read_only_part(part):
    ro = getattr(part, "read_only", None)
    return ro() if callable(ro) else part
