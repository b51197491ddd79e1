"""The fitted orbit and its covariance at other times: x(t) from the dynamics, P(t) by the unscented
transform of the fit covariance (:mod:`.unscented_prediction`, the default) or linearly,
P(t) = Phi(t, t0) P Phi(t, t0)^T."""
from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from cistrack.errors import ConfigError, StateError
from cistrack.least_squares.result import FitResult
from cistrack.least_squares.solve_for_parameters import fitted_dynamics
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.least_squares.unscented_prediction import unscented_covariances
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["predict", "predict_orbit", "Prediction", "COVARIANCE_METHODS"]

COVARIANCE_METHODS = ("unscented", "linear")
"""How :func:`predict` carries the covariance: ``unscented`` (sigma points through the nonlinear
dynamics: right where the flow bends within the covariance, e.g. at a close perilune) or
``linear`` (transition matrices: exact for linear dynamics, too thin where the flow bends)."""


class Prediction(NamedTuple):
    """A fit carried to other times (K of them)."""

    states: np.ndarray
    """(K, 6) [LU, VU]"""
    covariances: np.ndarray
    """(K, 6, 6) [LU, VU]"""
    linear: np.ndarray
    """(K,) bool: where the covariance is the linear one (all of them for ``covariance='linear'``;
    with ``unscented``, the times on and after a sigma-point orbit hit a body or failed, or all of
    them when the fit covariance gives no sigma points: not finite or not positive semi-definite)"""


def predict_orbit(result: FitResult, dynamics: Dynamics, times: Any, *,
                  covariance: str = "unscented") -> Prediction:
    """The fit ``result`` at ``times`` (K,) TU, before, inside or after the arc: states from the
    dynamics' ``propagate_with_stm`` and covariances by ``covariance`` (one of
    :data:`COVARIANCE_METHODS`). Raises :class:`cistrack.errors.StateError` for non-finite times,
    :class:`cistrack.errors.ConfigError` for an unknown method and
    :class:`cistrack.errors.PropagationError` when the fitted orbit hits a body. Solve-for
    parameters the fit estimated (``result.parameter_names``, e.g. the area-to-mass ratio) are
    applied to ``dynamics`` and held at their estimates; the covariance is the state's."""
    if covariance not in COVARIANCE_METHODS:
        raise ConfigError(f"covariance={covariance!r}: must be one of {', '.join(COVARIANCE_METHODS)}")
    tt = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
    if tt.size == 0 or not np.all(np.isfinite(tt)):
        raise StateError("fit prediction: times must be one or more finite numbers (TU)")
    dynamics = fitted_dynamics(dynamics, result)  # with the parameters the fit estimated
    states, stms = arc_states_and_stms(dynamics, result.state, result.epoch, tt)
    cov = np.einsum("kij,jl,kml->kim", stms, result.covariance, stms)
    cov = 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
    linear = np.ones(tt.size, dtype=bool)
    if covariance == "unscented":
        try:
            sigma, ok = unscented_covariances(dynamics, result.state, result.covariance, result.epoch, tt)
        except StateError:  # no sigma points (a covariance that is not positive semi-definite or not
            return Prediction(states, cov, linear)  # finite, e.g. a forced export): the linear map
        cov[ok] = sigma[ok]
        linear = ~ok
    return Prediction(states, cov, linear)


def predict(result: FitResult, dynamics: Dynamics, times: Any, *,
            covariance: str = "unscented") -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) [LU, VU] and covariances (K, 6, 6) of a fit at ``times`` (K,) TU, before,
    inside or after the arc (:func:`predict_orbit`; ``covariance='linear'`` for the transition
    matrices' P(t) = Phi P Phi^T). Raises
    :class:`cistrack.errors.StateError` for non-finite times and
    :class:`cistrack.errors.PropagationError` when the orbit hits a body."""
    p = predict_orbit(result, dynamics, times, covariance=covariance)
    return p.states, p.covariances
