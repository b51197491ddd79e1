"""Bootstrap (sampling importance resampling) particle filter: the classic baseline.

Particles are propagated with the dynamics (the bootstrap proposal) and weighted by the
measurement likelihood N(z; h(x), R) in the log domain; when the effective sample size falls
below ``resample_threshold`` x N they are resampled systematically. With arcsecond angles and a
large IOD cloud almost every weight vanishes at the first measurement: particle depletion,
visible in the ``ess`` and ``unique_particles`` diagnostics.
"""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import Belief, ParticleCloud
from cistrack.interfaces.component import check_int, check_range
from cistrack.errors import FilterError
from cistrack import hookimpl
from cistrack.interfaces import Dynamics, Sensor
from cistrack.interfaces.filter import FilterBase
from cistrack.model.measurement import Measurement

from .particle_declarations import ParticleFilterDeclarations
from .ensemble_propagation import propagate_particles
from .gaussian_belief import single_gaussian
from .initial_cloud import check_cloud, initial_particles
from .measured_components import MeasuredComponents, check_epoch
from .resampling import effective_sample_size, normalize_log_weights, systematic_resample
from .process_noise import check_velocity_noise

__all__ = ["SIRFilter"]

_LOG_2PI = float(np.log(2.0 * np.pi))


class SIRFilter(ParticleFilterDeclarations, FilterBase):
    """Bootstrap particle filter with log weights and systematic resampling.

    Parameters
    ----------
    n_particles : int
        Number of particles N.
    resample_threshold : float
        Resample when ESS < resample_threshold * N (1 = every step, 0 = never).
    velocity_noise_kms_per_sqrt_day : float
        Process noise: velocity random walk, km/s after one day (0 = off).
    """

    default_name = "sir"
    stacked_updates = True  # reads measurements only through MeasuredComponents

    def __init__(self, n_particles: int = 10000, resample_threshold: float = 0.5,
                 velocity_noise_kms_per_sqrt_day: float = 0.0):
        self.n_particles = check_int(self, "n_particles", n_particles, minimum=2)
        self.resample_threshold = check_range(self, "resample_threshold", resample_threshold, 0.0, 1.0)
        self.velocity_noise_kms_per_sqrt_day = check_velocity_noise(self, velocity_noise_kms_per_sqrt_day)
        self._x: np.ndarray | None = None

    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """``n_particles`` equally weighted particles from the cloud at ``cloud.epoch``."""
        check_cloud(cloud, self._who(), dynamics, sensor, rng)
        self._x = initial_particles(cloud, self.n_particles, rng)
        self._logw = np.full(self._x.shape[0], -np.log(self._x.shape[0]))
        self._dyn, self._sensor, self._rng = dynamics, sensor, rng
        self._t = float(cloud.epoch)
        self._lost_total = 0
        self._diag: dict[str, float] = {}
        self._refresh_diag()

    def _predict_to(self, t: float) -> None:
        """Propagate every particle to ``t`` (TU); particles that hit a body are removed."""
        x, alive, _ = propagate_particles(self._dyn, self._x, self._t, t, self._who(),
                                       self.velocity_noise_kms_per_sqrt_day, self._rng)
        lost = int(np.count_nonzero(~alive))
        self._x = x
        self._logw, _ = normalize_log_weights(self._logw[alive], self._who())
        self._lost_total += lost
        self._t = t
        self._diag = {"particles_lost_step": float(lost)}
        self._refresh_diag()

    def update(self, measurement: Measurement) -> None:
        """Multiply the weights by the measurement likelihood; resample if the ESS is low."""
        self._require_init()
        check_epoch(self._t, measurement, self._who())
        meas = MeasuredComponents(self._sensor, measurement)
        d = meas.residuals_to_measurement(self._x)
        if not np.all(np.isfinite(d)):
            raise FilterError(f"filter '{self._who()}': the sensor returned NaN predicted measurements")
        L = np.linalg.cholesky(meas.R)
        sol = np.linalg.solve(L, d.T)
        loglik = -0.5 * (np.sum(sol * sol, axis=0) + 2.0 * np.sum(np.log(np.diag(L))) + d.shape[1] * _LOG_2PI)
        self._logw, log_evidence = normalize_log_weights(self._logw + loglik, self._who())
        w = np.exp(self._logw)
        ess = effective_sample_size(w)
        resampled = ess < self.resample_threshold * self.n_particles
        if resampled:
            idx = systematic_resample(w, self.n_particles, self._rng)
            self._x = self._x[idx]
            self._logw = np.full(self.n_particles, -np.log(self.n_particles))
        self._diag.update({"log_likelihood": float(log_evidence), "ess_before_resampling": ess,
                           "resampled": float(resampled)})
        self._refresh_diag()

    @property
    def belief(self) -> Belief:
        """Moment-matched Gaussian of the weighted particles, and the weighted particles."""
        self._require_init()
        w = np.exp(self._logw)
        cloud = ParticleCloud(self._x, self._t, w)
        return Belief(self._t, single_gaussian(cloud.mean, cloud.covariance), cloud)

    def _refresh_diag(self) -> None:
        w = np.exp(self._logw)
        self._diag.update({"n_components": 1.0, "n_particles": float(self._x.shape[0]),
                           "ess": effective_sample_size(w),
                           "unique_particles": float(np.unique(self._x[:, 0]).size),
                           "particles_lost": float(self._lost_total)})

    def _is_initialized(self) -> bool:
        return self._x is not None


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "sir", SIRFilter)
