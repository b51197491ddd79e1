"""Turning the IOD cloud into a filter's starting particles."""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.errors import FilterError, ParameterError

from .resampling import systematic_resample

__all__ = ["check_cloud", "initial_particles"]


def initial_particles(cloud: ParticleCloud, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` equally weighted particles (n, d) from ``cloud``: systematic resampling of a weighted
    cloud, a subsample without replacement of a larger one, all particles plus draws with
    replacement of a smaller one."""
    x = np.asarray(cloud.states, dtype=float)
    if cloud.weights is not None:
        return x[systematic_resample(cloud.weights, n, rng)]
    if x.shape[0] >= n:
        return x[rng.choice(x.shape[0], size=n, replace=False)] if x.shape[0] > n else x.copy()
    extra = rng.integers(0, x.shape[0], size=n - x.shape[0])
    return np.concatenate([x, x[extra]])


def check_cloud(cloud: ParticleCloud, who: str) -> None:
    """Raise a clear error for an empty or non-finite initial cloud."""
    if not isinstance(cloud, ParticleCloud):
        raise ParameterError(f"filter '{who}': initialize() needs a ParticleCloud, got {type(cloud).__name__}")
    if len(cloud) == 0 or cloud.states.ndim != 2:
        raise FilterError(f"filter '{who}': the initial cloud is empty")
    if not np.all(np.isfinite(cloud.states)):
        raise FilterError(f"filter '{who}': the initial cloud contains NaN or infinite states")
