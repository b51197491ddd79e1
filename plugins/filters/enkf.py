"""Ensemble Kalman filter on filterpy's EnsembleKalmanFilter, vectorised over members.

filterpy propagates and measures members one at a time, draws its perturbations from numpy's
global random state and defaults Q to the identity (one LU^2: enormous). The subclass here
propagates all members with one ``dynamics.propagate`` call, measures them with one
``sensor.measure`` call, draws every perturbation from the run's Generator and sets Q from the
filter's process-noise parameter (zero by default). The update is the stochastic (perturbed
observation) EnKF with innovations taken relative to the measurement, so angles wrap correctly.
"""
from __future__ import annotations

import numpy as np
from filterpy.kalman import EnsembleKalmanFilter

from cistrack.belief import Belief, ParticleCloud, sample_covariance
from cistrack.component import check_int, check_nonnegative
from cistrack.errors import FilterError
from cistrack.hookspecs import hookimpl
from cistrack.interfaces import Dynamics, Filter, Sensor
from cistrack.measurement import Measurement

from .ensemble_propagation import propagate_ensemble
from .gaussian_belief import single_gaussian
from .initial_cloud import check_cloud, initial_particles
from .kalman_update import group_moments, kalman_gains
from .observation import MeasuredComponents, check_epoch
from .process_noise import velocity_random_walk_covariance

__all__ = ["EnKFFilter"]


def _not_used(*args, **kwargs):  # filterpy requires fx/hx; the batch methods never call them
    raise FilterError("internal: per-member fx/hx must not be called")


class _BatchEnKF(EnsembleKalmanFilter):
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
        final, alive = propagate_ensemble(dynamics, self.sigmas, t0, t1, who)
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


class EnKFFilter(Filter):
    """Stochastic ensemble Kalman filter (filterpy) started from the IOD cloud's particles.

    Parameters
    ----------
    n_members : int
        Ensemble size; the IOD cloud is subsampled (or resampled) to it.
    velocity_noise_kms_per_sqrt_day : float
        Process noise Q: velocity random walk, km/s after one day (0 = none).
    """

    def __init__(self, n_members: int = 1000, velocity_noise_kms_per_sqrt_day: float = 0.0):
        self.n_members = check_int(self, "n_members", n_members, minimum=2)
        self.velocity_noise_kms_per_sqrt_day = check_nonnegative(
            self, "velocity_noise_kms_per_sqrt_day", velocity_noise_kms_per_sqrt_day)
        self._enkf: _BatchEnKF | None = None

    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """Members are ``n_members`` particles of the cloud at ``cloud.epoch``."""
        check_cloud(cloud, self._who())
        members = initial_particles(cloud, self.n_members, rng)
        self._enkf = _BatchEnKF(members, max(1, len(sensor.names)), rng)
        self._dyn, self._sensor = dynamics, sensor
        self._t = float(cloud.epoch)
        self._lost_total = 0
        self._diag: dict[str, float] = {"n_components": 1.0, "n_members": float(members.shape[0])}

    def predict(self, t: float) -> None:
        """Propagate every member to ``t`` (TU); members that hit a body are removed and counted."""
        enkf = self._require_init()
        t = float(t)
        if t == self._t:
            return
        enkf.Q = velocity_random_walk_covariance(self.velocity_noise_kms_per_sqrt_day, t - self._t, enkf.dim_x)
        lost = enkf.predict_batch(self._dyn, self._t, t, self._who())
        self._lost_total += lost
        self._t = t
        self._diag = {"n_components": 1.0, "n_members": float(enkf.N), "particles_lost_step": float(lost)}

    def update(self, measurement: Measurement) -> None:
        """Perturbed-observation update of every member with ``measurement``."""
        enkf = self._require_init()
        check_epoch(self._t, measurement, self._who())
        meas = MeasuredComponents(self._sensor, measurement)
        self._diag["log_likelihood"] = enkf.update_batch(meas, self._who())
        if not np.all(np.isfinite(enkf.sigmas)):
            raise FilterError(f"filter '{self._who()}': the update produced non-finite members")

    @property
    def belief(self) -> Belief:
        """The ensemble's Gaussian (a mixture of one) with the members as samples."""
        enkf = self._require_init()
        return Belief(self._t, single_gaussian(enkf.x, enkf.P), ParticleCloud(enkf.sigmas.copy(), self._t))

    @property
    def diagnostics(self) -> dict[str, float]:
        d = dict(self._diag)
        d["particles_lost"] = float(self._lost_total)
        return d

    def _who(self) -> str:
        return self.registry_name or "enkf"

    def _require_init(self) -> _BatchEnKF:
        if self._enkf is None:
            raise FilterError(f"filter '{self._who()}': call initialize() first")
        return self._enkf


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "enkf", EnKFFilter)
