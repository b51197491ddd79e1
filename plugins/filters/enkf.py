"""Ensemble Kalman filter on filterpy's EnsembleKalmanFilter, vectorised over members.

filterpy propagates and measures members one at a time, draws its perturbations from numpy's
global random state and defaults Q to the identity (one LU^2: enormous). The subclass here
propagates all members with one ``dynamics.propagate`` call, measures them with one
``sensor.measure`` call, draws every perturbation from the run's Generator and sets Q from the
filter's process-noise parameter (zero by default). The update is the stochastic (perturbed
observation) EnKF with innovations taken relative to the measurement, so angles wrap correctly.
"""
from __future__ import annotations

import warnings

import numpy as np

from cistrack.model.belief import Belief, ParticleCloud
from cistrack.interfaces.component import check_int
from cistrack.errors import FilterError
from cistrack import hookimpl
from cistrack.interfaces import Dynamics, Sensor
from cistrack.interfaces.filter import FilterBase
from cistrack.model.measurement import Measurement

from .particle_declarations import ParticleFilterDeclarations
from .gaussian_belief import single_gaussian
from .initial_cloud import check_cloud, initial_particles
from .measured_components import MeasuredComponents, check_epoch
from .process_noise import check_velocity_noise, velocity_random_walk_covariance

__all__ = ["EnKFFilter", "MIN_MEMBERS"]

MIN_MEMBERS = 7
"""Fewest ensemble members (n_particles) the EnKF takes: one more than the state's dimension (6).
The update moves the state only within the span of the members' deviations from their mean, of
rank at most n_particles - 1: with fewer than 7 some direction of position and velocity has no
spread, the filter can never correct it, and its belief collapses (2 members ran to 'diverged').
Seven is the floor of a full-rank covariance, not a recommendation: the default is 1000."""


class EnKFFilter(ParticleFilterDeclarations, FilterBase):
    """Stochastic ensemble Kalman filter (filterpy) started from the IOD cloud's particles.

    Parameters
    ----------
    n_particles : int
        Ensemble size (members), at least 7 (:data:`MIN_MEMBERS`: one more than the state's 6
        dimensions, for a full-rank ensemble covariance); the IOD cloud is subsampled (or
        resampled) to it.
    velocity_noise_kms_per_sqrt_day : float
        Process noise Q: velocity random walk, km/s after one day (0 = none).
    n_members : int or None
        Deprecated name of n_particles (every particle filter takes n_particles); still accepted
        with a FutureWarning, and an error when both are given.
    """

    default_name = "enkf"
    stacked_updates = True  # reads measurements only through MeasuredComponents

    def __init__(self, n_particles: int = 1000, velocity_noise_kms_per_sqrt_day: float = 0.0,
                 n_members: int | None = None):
        if n_members is not None:
            if n_particles != 1000:
                self._fail("n_members", n_members, "is the deprecated name of n_particles; give only n_particles")
            n_members = self._members("n_members", n_members)
            warnings.warn("filter 'enkf': parameter 'n_members' is deprecated; use 'n_particles' "
                          "(the name every particle filter uses)", FutureWarning, stacklevel=2)
            n_particles = n_members
        self.n_particles = self._members("n_particles", n_particles)
        self.n_members = None  # the deprecated alias is folded into n_particles
        self.velocity_noise_kms_per_sqrt_day = check_velocity_noise(self, velocity_noise_kms_per_sqrt_day)
        self._enkf = None  # an enkf_batch.BatchEnKF once initialised

    def _members(self, name: str, value) -> int:
        """``value`` of the parameter ``name`` as an ensemble size; ParameterError below :data:`MIN_MEMBERS`."""
        n = check_int(self, name, value)
        if n < MIN_MEMBERS:
            self._fail(name, value, f"must be >= {MIN_MEMBERS} (the state's 6 dimensions + 1): the ensemble covariance "
                                    f"has rank at most {name} - 1, so fewer members leave a direction of position and "
                                    "velocity that the update can never correct, and the filter collapses; the "
                                    "default is 1000")
        return n

    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """Members are ``n_particles`` particles of the cloud at ``cloud.epoch``."""
        check_cloud(cloud, self._who(), dynamics, sensor, rng)
        members = initial_particles(cloud, self.n_particles, rng)
        from .enkf_batch import BatchEnKF  # filterpy, imported on use

        self._enkf = BatchEnKF(members, max(1, len(sensor.names)), rng)
        self._dyn, self._sensor = dynamics, sensor
        self._t = float(cloud.epoch)
        self._lost_total = 0
        self._diag: dict[str, float] = {"n_components": 1.0, "n_members": float(members.shape[0])}

    def _predict_to(self, t: float) -> None:
        """Propagate every member to ``t`` (TU); members that hit a body are removed and counted."""
        enkf = self._enkf
        enkf.Q = velocity_random_walk_covariance(self.velocity_noise_kms_per_sqrt_day, t - self._t, enkf.dim_x)
        lost = enkf.predict_batch(self._dyn, self._t, t, self._who())
        self._lost_total += lost
        self._t = t
        self._diag = {"n_components": 1.0, "n_members": float(enkf.N), "particles_lost_step": float(lost)}

    def update(self, measurement: Measurement) -> None:
        """Perturbed-observation update of every member with ``measurement``."""
        self._require_init()
        enkf = self._enkf
        check_epoch(self._t, measurement, self._who())
        meas = MeasuredComponents(self._sensor, measurement)
        self._diag["log_likelihood"] = enkf.update_batch(meas, self._who())
        if not np.all(np.isfinite(enkf.sigmas)):
            raise FilterError(f"filter '{self._who()}': the update produced non-finite members")

    @property
    def belief(self) -> Belief:
        """The ensemble's Gaussian (a mixture of one) with the members as samples."""
        self._require_init()
        enkf = self._enkf
        return Belief(self._t, single_gaussian(enkf.x, enkf.P), ParticleCloud(enkf.sigmas.copy(), self._t))

    def _totals(self) -> dict[str, float]:
        return {"particles_lost": float(self._lost_total)}

    def _is_initialized(self) -> bool:
        return self._enkf is not None


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "enkf", EnKFFilter)
