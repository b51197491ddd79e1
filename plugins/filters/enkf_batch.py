"""filterpy's EnsembleKalmanFilter with whole-ensemble propagation and an explicit Generator.

Kept apart from :mod:`.enkf` so that the registry can list the ``enkf`` filter without
importing filterpy (which imports matplotlib): :class:`~.enkf.EnKFFilter` imports this module
when it is initialised.
"""
from __future__ import annotations

import numpy as np
from filterpy.kalman import EnsembleKalmanFilter

from cistrack.model.belief import sample_covariance
from cistrack.errors import FilterError
from cistrack.interfaces import Dynamics

from .ensemble_propagation import propagate_ensemble
from .kalman_update import group_moments, kalman_gains
from .measured_components import MeasuredComponents

__all__ = ["BatchEnKF"]


def _not_used(*args, **kwargs):  # filterpy requires fx/hx; the batch methods never call them
    raise FilterError("internal: per-member fx/hx must not be called")


class BatchEnKF(EnsembleKalmanFilter):
    """EnsembleKalmanFilter with whole-ensemble propagation and update and an explicit Generator."""

    def __init__(self, members: np.ndarray, dim_z: int, rng: np.random.Generator):
        self._initial_members = np.array(members, dtype=float)
        self.rng = rng
        super().__init__(x=members.mean(axis=0), P=sample_covariance(members), dim_z=dim_z, dt=0.0,
                         N=members.shape[0], hx=_not_used, fx=_not_used)
        self.Q = np.zeros((self.dim_x, self.dim_x))  # filterpy's default Q = I is one LU^2

    def initialize(self, x, P):
        """Use the given members instead of filterpy's draw from global random state."""
        self.sigmas = self._initial_members.copy()
        self.x = self.sigmas.mean(axis=0)
        self.P = sample_covariance(self.sigmas)
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    def _moments(self) -> None:
        self.x = self.sigmas.mean(axis=0)
        self.P = sample_covariance(self.sigmas)

    def predict_batch(self, dynamics: Dynamics, t0: float, t1: float, who: str) -> int:
        """Propagate all members; drop those that hit a body. Returns the number dropped."""
        final, alive, _ = propagate_ensemble(dynamics, self.sigmas, t0, t1, who)
        lost = int(np.count_nonzero(~alive))
        if lost == self.sigmas.shape[0]:
            raise FilterError(f"filter '{who}': every ensemble member hit a body before t = {t1} TU")
        self.sigmas = final[alive]
        self.N = self.sigmas.shape[0]
        if np.any(self.Q):
            sd = np.sqrt(np.clip(np.diag(self.Q), 0.0, None))
            self.sigmas = self.sigmas + self.rng.standard_normal(self.sigmas.shape) * sd
        self._moments()
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        return lost

    def update_batch(self, meas: MeasuredComponents, who: str) -> float:
        """Perturbed-observation update of every member; returns the log-likelihood of z."""
        d = meas.residuals_to_measurement(self.sigmas)  # h(x_j) - z, wrapped
        if not np.all(np.isfinite(d)):
            raise FilterError(f"filter '{who}': the sensor returned NaN predicted measurements")
        labels = np.zeros(self.sigmas.shape[0], dtype=np.intp)
        mom = group_moments(self.sigmas, d, labels, 1)
        gains = kalman_gains(mom, meas.R)
        self.S = gains.S[0]
        self.SI = np.linalg.inv(self.S)
        self.K = gains.K[0]
        e = self.rng.standard_normal(d.shape) @ np.linalg.cholesky(meas.R).T
        # x_j + K (z + e_j - h(x_j)) with z - h(x_j) = -d_j
        self.sigmas = self.sigmas + (e - d) @ self.K.T
        self._moments()
        self.z = meas.z.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        nu = gains.nu[0]
        return float(-0.5 * (nu @ self.SI @ nu + np.linalg.slogdet(self.S)[1] + nu.size * np.log(2 * np.pi)))
