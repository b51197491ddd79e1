"""filterpy's UnscentedKalmanFilter with whole-ensemble propagation and iterated updates.

Kept apart from :mod:`.ukf` so that the registry can list the ``ukf`` filter without
importing filterpy (which imports matplotlib): :class:`~.ukf.UKFFilter` imports this module
when it is initialised.
"""
from __future__ import annotations

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints as _FilterpyMerwe
from filterpy.kalman import UnscentedKalmanFilter
from scipy.linalg import cholesky

from cistrack.model.belief import regularize_covariance
from cistrack.errors import FilterError
from cistrack.interfaces import Dynamics

from .ensemble_propagation import propagate_ensemble
from .measured_components import MeasuredComponents
from .posterior_linearization import posterior_linearization_update
from .sigma_points import merwe_points

__all__ = ["BatchUKF", "MerweScaledSigmaPoints", "robust_sqrt", "batch_unscented_transform"]


class MerweScaledSigmaPoints(_FilterpyMerwe):
    """filterpy's ``MerweScaledSigmaPoints`` (same constructor, points and weights bit for bit)
    whose ``sigma_points`` forms the 2n points x -/+ U[k] in two array operations instead of 2n
    row operations (the same subtractions, so the same numbers): the UKF forms them several times
    per step, and each row operation cost microseconds."""

    def sigma_points(self, x, P):
        if self.subtract is not np.subtract or np.isscalar(x) or np.isscalar(P) or self.n != np.size(x):
            return super().sigma_points(x, P)
        lambda_ = self.alpha ** 2 * (self.n + self.kappa) - self.n
        return merwe_points(np.asarray(x), self.sqrt((lambda_ + self.n) * np.atleast_2d(P)))


def robust_sqrt(a: np.ndarray) -> np.ndarray:
    """Upper Cholesky factor of ``a`` (filterpy's convention), regularising a matrix that is not
    numerically positive definite."""
    try:
        return cholesky(a)
    except np.linalg.LinAlgError:
        return cholesky(regularize_covariance(a, 1e-10))


def _not_used(*args, **kwargs):  # filterpy requires fx/hx; the batch overrides never call them
    raise FilterError("internal: per-point fx/hx must not be called")


def batch_unscented_transform(sigmas, Wm, Wc, noise_cov=None, mean_fn=None, residual_fn=None):
    """filterpy's unscented transform without its loop over sigma points: (K, n) -> mean, cov."""
    x = Wm @ sigmas if mean_fn is None else mean_fn(sigmas, Wm)
    y = sigmas - x if residual_fn is None or residual_fn is np.subtract else residual_fn(sigmas, x)
    P = (y.T * Wc) @ y
    if noise_cov is not None:
        P = P + noise_cov
    return x, P


class BatchUKF(UnscentedKalmanFilter):
    """UnscentedKalmanFilter whose sigma points go through dynamics and sensor as one array."""

    def __init__(self, dynamics: Dynamics, who: str, **kw):
        super().__init__(hx=_not_used, fx=_not_used, dt=0.0, **kw)
        self.dynamics = dynamics
        self.who = who
        self.t0 = 0.0
        self.n_lost_last = 0
        self.iterations_last = 0
        self.step_last = 0.0

    def compute_process_sigmas(self, dt, fx=None, **fx_args):
        sigmas = self.points_fn.sigma_points(self.x, self.P)
        final, alive, _ = propagate_ensemble(self.dynamics, sigmas, self.t0, self.t0 + dt, self.who)
        # a sigma point that hit a body keeps its impact state (the transform needs all points)
        self.n_lost_last = int(np.count_nonzero(~alive))
        self.sigmas_f = final

    def update_iterated(self, meas: MeasuredComponents, max_iterations: int, tolerance: float) -> None:
        """The measurement update, iterated by posterior linearisation (one iteration = the
        ordinary UKF update); all sigma points are measured with one sensor call per iteration."""
        try:
            res = posterior_linearization_update(self.points_fn, self.x, self.P, meas.residuals_to_measurement,
                                                 meas.R, max_iterations, tolerance)
        except (FilterError, np.linalg.LinAlgError) as exc:
            raise FilterError(f"filter '{self.who}': measurement update failed: {exc}") from None
        self.x, self.P = res.x, res.P
        self.y, self.S = res.innovation, res.S
        self.SI = np.linalg.inv(self.S)
        self.iterations_last, self.step_last = res.iterations, res.step
        self.z = meas.z.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self._log_likelihood = self._likelihood = self._mahalanobis = None
