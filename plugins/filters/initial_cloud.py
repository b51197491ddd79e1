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


def check_cloud(cloud: ParticleCloud, who: str, dynamics=None, sensor=None, rng=None) -> None:
    """Raise a clear error for an initial cloud that is empty, of one particle, not (N, 6) or not
    finite, and (when given) for ``dynamics``, ``sensor`` and ``rng`` that are not what
    ``initialize()`` takes (a Dynamics, a sensor with ``measure``, a numpy Generator)."""
    if not isinstance(cloud, ParticleCloud):
        raise ParameterError(f"filter '{who}': initialize() needs a ParticleCloud, got {type(cloud).__name__}")
    if len(cloud) == 0 or cloud.states.ndim != 2:
        raise FilterError(f"filter '{who}': the initial cloud is empty")
    if cloud.states.shape[1] != 6:
        raise FilterError(f"filter '{who}': the initial cloud's states have {cloud.states.shape[1]} columns; "
                          "a state is 6 numbers (synodic position LU and velocity VU)")
    if len(cloud) < 2:
        raise FilterError(f"filter '{who}': the initial cloud has 1 particle; a belief needs a spread of states")
    if not np.all(np.isfinite(cloud.states)):
        raise FilterError(f"filter '{who}': the initial cloud contains NaN or infinite states")
    _check_parts(who, dynamics, sensor, rng)


def _check_parts(who: str, dynamics, sensor, rng) -> None:
    from cistrack.interfaces.dynamics import Dynamics

    if dynamics is not None and not isinstance(dynamics, Dynamics):
        raise ParameterError(f"filter '{who}': initialize() needs a Dynamics model (e.g. "
                             f"registry.create('dynamics', 'cr3bp')), got {type(dynamics).__name__}")
    if sensor is not None and not callable(getattr(sensor, "measure", None)):
        raise ParameterError(f"filter '{who}': initialize() needs a sensor (with measure()), got {type(sensor).__name__}")
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ParameterError(f"filter '{who}': initialize() needs a numpy Generator (np.random.default_rng(seed)), "
                             f"got {type(rng).__name__}")
