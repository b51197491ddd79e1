"""The PGM's ``pgm-kernel`` step: ``after-gap`` (kernels through the first pass after a gap, at
sharp measurements) and ``off``. The kernel update itself: :mod:`.kernel_update`."""
from __future__ import annotations

from typing import Callable

import numpy as np

from cistrack.interfaces.component import check_positive, check_range
from cistrack.interfaces.pgm_steps import ClusteredParticles, KernelRun, KernelUpdate

from .kernel_update import PassAfterGap, kernel_update

__all__ = ["AfterGapKernels", "NoKernels"]


class AfterGapKernels(KernelUpdate):
    """In the first pass after a gap, at a measurement far sharper than the cloud, every particle
    is conditioned as its own Gaussian kernel (its cluster's covariance times Silverman's bandwidth)
    instead of the clusters' Gaussians.

    Parameters
    ----------
    kernel_ess : float
        Kernels at a measurement whose likelihood weights' effective sample size is below this
        fraction of the particles; 0 = never (the PGM's default), 1 = every update of that pass.
    reanchor_gap_days : float
        A gap between updates at least this long starts a pass after a gap.
    reanchor_pause_hours : float
        A pause between updates at least this long ends a pass.
    """

    def __init__(self, kernel_ess: float = 0.0, reanchor_gap_days: float = 5.0, reanchor_pause_hours: float = 3.0):
        self.kernel_ess = check_range(self, "kernel_ess", kernel_ess, 0.0, 1.0)
        self.reanchor_gap_days = check_positive(self, "reanchor_gap_days", reanchor_gap_days)
        self.reanchor_pause_hours = check_positive(self, "reanchor_pause_hours", reanchor_pause_hours)

    def start(self) -> "_AfterGapRun | None":
        """A fresh state for one run; None when ``kernel_ess`` is 0."""
        if not self.kernel_ess > 0:
            return None
        return _AfterGapRun(self.kernel_ess, PassAfterGap(self.reanchor_gap_days, self.reanchor_pause_hours))


class _AfterGapRun(KernelRun):
    """One run of :class:`AfterGapKernels`: the passes seen so far."""

    def __init__(self, kernel_ess: float, passes: PassAfterGap) -> None:
        self.kernel_ess = kernel_ess
        self.passes = passes

    def due(self, t: float, sharpness: Callable[[], float]) -> bool:
        """In a pass after a gap (``t`` TU recorded as the latest update), and sharper than ``kernel_ess``."""
        return self.passes.at(t) and sharpness() < self.kernel_ess

    def update(self, prior: ClusteredParticles, residuals: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
               n: int, rng: np.random.Generator, who: str) -> tuple[np.ndarray, np.ndarray, float]:
        """``n`` particles (n, d) from the conditioned kernels, their clusters (n,), the log evidence."""
        samples, labels, log_evidence, _ = kernel_update(prior, residuals, R, n, rng, who)
        return samples, labels, log_evidence


class NoKernels(KernelUpdate):
    """No kernel updates: the clusters' Gaussians at every measurement."""

    def start(self) -> None:
        """None: this run never conditions kernels."""
        return None
