"""The fitted orbit and its covariance at other times: x(t) and P(t) = Phi(t, t0) P Phi(t, t0)^T."""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.errors import StateError
from cistrack.fit.result import FitResult
from cistrack.fit.trajectory import arc_states_and_stms
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["predict"]


def predict(result: FitResult, dynamics: Dynamics, times: Any) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) [LU, VU] and covariances (K, 6, 6) of a fit at ``times`` (K,) TU, before,
    inside or after the arc (linear covariance propagation with the dynamics' transition
    matrices). Raises :class:`cistrack.errors.StateError` for non-finite times and
    :class:`cistrack.errors.PropagationError` when the orbit hits a body."""
    tt = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
    if tt.size == 0 or not np.all(np.isfinite(tt)):
        raise StateError("fit prediction: times must be one or more finite numbers (TU)")
    states, stms = arc_states_and_stms(dynamics, result.state, result.epoch, tt)
    cov = np.einsum("kij,jl,kml->kim", stms, result.covariance, stms)
    return states, 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
