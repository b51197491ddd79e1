"""Regularised particle filter with progressive correction: a particle baseline that survives
arcsecond measurements.

The bootstrap filter (``sir``) multiplies a wide prior by a likelihood of 1.5 arcsec at once, and
nearly every weight vanishes (effective sample size ~1). This filter (``rpf``) brings the
likelihood in gradually and regularises after each stage:

1. the log likelihood l_i of each particle is tempered: weights w_i * exp(beta l_i), with beta
   the largest step (up to what is left of 1) that keeps the effective sample size at
   ``ess_target`` x N (bisection on beta);
2. the particles are resampled (systematic) and moved by a Gaussian kernel: with the weighted
   mean m and covariance S = L L^T before resampling,

       x_i' = a x_i + (1 - a) m + h L eps_i,    eps_i ~ N(0, I6),   a = sqrt(1 - h^2),

   the shrunk kernel of Liu & West, which keeps the mean and covariance of the cloud (without
   ``shrink`` x_i' = x_i + h L eps_i, the plain regularised filter of Musso, Oudjane & Le Gland,
   which inflates the covariance by 1 + h^2). The bandwidth h is Silverman's rule for a Gaussian
   kernel, (4 / (N (d + 2)))^(1 / (d + 4)), or Scott's, N^(-1 / (d + 4)), with d = 6, times
   ``bandwidth_scale``;
3. the likelihood of the moved particles is recomputed and the next stage follows, until the
   exponents sum to 1 (at most ``max_stages``; the rest is then applied in one step).

Diagnostics: ``stages`` of the last update, ``ess_before_resampling`` (the smallest effective
sample size of any stage: with ``max_stages`` reached it shows the degeneracy) and
``unique_particles``.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_choice, check_int, check_positive, check_range
from cistrack.errors import FilterError
from cistrack import hookimpl
from cistrack.model.measurement import Measurement

from .measured_components import MeasuredComponents, check_epoch
from .resampling import effective_sample_size, normalize_log_weights, systematic_resample
from .sir import SIRFilter

__all__ = ["RegularizedSIRFilter", "kernel_bandwidth"]

_LOG_2PI = float(np.log(2.0 * np.pi))
_DIM = 6


def kernel_bandwidth(n: int, rule: str, dim: int = _DIM) -> float:
    """Optimal Gaussian-kernel bandwidth (in units of the cloud's standard deviation) for ``n``
    particles in ``dim`` dimensions: 'silverman' (4 / (n (dim + 2)))^(1 / (dim + 4)) or
    'scott' n^(-1 / (dim + 4))."""
    if rule == "silverman":
        return float((4.0 / (n * (dim + 2.0))) ** (1.0 / (dim + 4.0)))
    if rule == "scott":
        return float(n ** (-1.0 / (dim + 4.0)))
    raise ValueError(f"unknown bandwidth rule {rule!r}; allowed: 'silverman', 'scott'")


def _tempering_step(logw: np.ndarray, loglik: np.ndarray, remaining: float, target: float) -> float:
    """The largest beta in (0, remaining] whose tempered weights keep ESS >= target (bisection)."""
    def ess(beta: float) -> float:
        lw = logw + beta * loglik
        w = np.exp(lw - lw.max())
        return float(w.sum() ** 2 / np.sum(w * w))

    if ess(remaining) >= target:
        return remaining
    lo, hi = 0.0, remaining
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if ess(mid) >= target:
            lo = mid
        else:
            hi = mid
    return max(lo, 1e-12 * remaining)


class RegularizedSIRFilter(SIRFilter):
    """Regularised particle filter: the likelihood brought in by tempering stages, each followed by
    resampling and a Gaussian-kernel move (see the module docstring).

    Parameters
    ----------
    n_particles : int
        Number of particles N.
    ess_target : float
        Each tempering stage keeps the effective sample size at this fraction of N.
    max_stages : int
        Most tempering stages per measurement; what is left is applied in one last step.
    bandwidth : str
        Kernel bandwidth rule: "silverman" or "scott".
    bandwidth_scale : float
        Factor on the rule's bandwidth (h must stay below 1 with ``shrink``).
    shrink : bool
        Shrink towards the mean so that the kernel keeps the cloud's mean and covariance.
    velocity_noise_kms_per_sqrt_day : float
        Process noise: velocity random walk, km/s after one day (0 = off).
    """

    default_name = "rpf"

    def __init__(self, n_particles: int = 10000, ess_target: float = 0.5, max_stages: int = 200,
                 bandwidth: str = "silverman", bandwidth_scale: float = 1.0, shrink: bool = True,
                 velocity_noise_kms_per_sqrt_day: float = 0.0):
        super().__init__(n_particles=n_particles, resample_threshold=1.0,
                         velocity_noise_kms_per_sqrt_day=velocity_noise_kms_per_sqrt_day)
        self.ess_target = check_range(self, "ess_target", ess_target, 0.0, 1.0, lo_open=True, hi_open=True)
        self.max_stages = check_int(self, "max_stages", max_stages, minimum=1)
        self.bandwidth = check_choice(self, "bandwidth", bandwidth, ("silverman", "scott"))
        self.bandwidth_scale = check_positive(self, "bandwidth_scale", bandwidth_scale)
        if not isinstance(shrink, bool):
            self._fail("shrink", shrink, "must be true or false")
        self.shrink = shrink
        if shrink and kernel_bandwidth(self.n_particles, self.bandwidth) * self.bandwidth_scale >= 1.0:
            self._fail("bandwidth_scale", bandwidth_scale,
                       "must keep the kernel bandwidth h below 1 when shrink is on")

    def _loglik(self, meas: MeasuredComponents) -> np.ndarray:
        d = meas.residuals_to_measurement(self._x)
        if not np.all(np.isfinite(d)):
            raise FilterError(f"filter '{self._who()}': the sensor returned NaN predicted measurements")
        L = np.linalg.cholesky(meas.R)
        sol = np.linalg.solve(L, d.T)
        return -0.5 * (np.sum(sol * sol, axis=0) + 2.0 * np.sum(np.log(np.diag(L))) + d.shape[1] * _LOG_2PI)

    def _regularize(self, w: np.ndarray) -> None:
        """Resample N particles by weights ``w`` (N,) and move them by the kernel."""
        mean = w @ self._x
        d = self._x - mean
        cov = (d * w[:, None]).T @ d
        vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
        root = vecs * np.sqrt(np.clip(vals, 0.0, None))
        n = self.n_particles
        h = kernel_bandwidth(n, self.bandwidth) * self.bandwidth_scale
        x = self._x[systematic_resample(w, n, self._rng)]
        if self.shrink:
            a = np.sqrt(1.0 - h * h)
            x = a * x + (1.0 - a) * mean
        self._x = x + h * self._rng.standard_normal((n, _DIM)) @ root.T
        self._logw = np.full(n, -np.log(n))

    def update(self, measurement: Measurement) -> None:
        """Bring the likelihood in by tempering stages, resampling and moving after each."""
        self._require_init()
        check_epoch(self._t, measurement, self._who())
        meas = MeasuredComponents(self._sensor, measurement)
        remaining, stages, log_evidence, min_ess = 1.0, 0, 0.0, float("inf")
        target = self.ess_target * self.n_particles
        while remaining > 0.0:
            loglik = self._loglik(meas)
            last = stages + 1 >= self.max_stages
            beta = remaining if last else _tempering_step(self._logw, loglik, remaining, target)
            self._logw, log_z = normalize_log_weights(self._logw + beta * loglik, self._who())
            log_evidence += log_z
            w = np.exp(self._logw)
            min_ess = min(min_ess, effective_sample_size(w))
            remaining = 0.0 if last or beta >= remaining else remaining - beta
            stages += 1
            self._regularize(w)
        self._diag.update({"log_likelihood": float(log_evidence), "ess_before_resampling": min_ess,
                           "resampled": 1.0, "stages": float(stages)})
        self._refresh_diag()


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "rpf", RegularizedSIRFilter)
