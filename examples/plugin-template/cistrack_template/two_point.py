"""Two-point IOD: positions at two epochs of the first pass, velocity by finite difference."""
from __future__ import annotations

import numpy as np

from cistrack import units
from cistrack.api import IODError, IODMethod, MeasurementSet, ParticleCloud, Sensor, check_int, check_positive

__all__ = ["TwoPointIOD"]


class TwoPointIOD(IODMethod):
    """Monte Carlo two-point initial orbit determination.

    For each sample: perturb the angles of the first and the last of the first
    ``n_measurements`` measurements with their noise; take the range at the last epoch from the
    measured range (when the sensor gives one and ``use_range`` is true) or uniformly from
    [``min_range_km``, ``max_range_km``]; take a range rate uniformly from
    ±``max_range_rate_kms``; turn both into synodic positions with the sensor's
    ``observer_position`` and ``line_of_sight``; and difference them for the velocity. Samples
    outside the range bounds or faster than ``max_speed_kms`` are dropped.

    Parameters
    ----------
    n_particles : int
        Particles in the cloud (N).
    n_measurements : int
        How many of the first measurements span the two epochs (>= 2).
    oversample : int
        Samples drawn per particle wanted, to survive pruning.
    use_range : bool
        Use a measured "range" component when the measurements have one.
    min_range_km, max_range_km : float
        Cislunar range bounds from the observer, km.
    max_range_rate_kms : float
        Largest range rate drawn, km/s.
    max_speed_kms : float
        Largest synodic speed kept, km/s.
    """

    def __init__(self, n_particles: int = 2000, n_measurements: int = 8, oversample: int = 5,
                 use_range: bool = True, min_range_km: float = 84_328.0, max_range_km: float = 550_000.0,
                 max_range_rate_kms: float = 1.5, max_speed_kms: float = 42.0):
        self.n_particles = check_int(self, "n_particles", n_particles, minimum=2)
        self.n_measurements = check_int(self, "n_measurements", n_measurements, minimum=2)
        self.oversample = check_int(self, "oversample", oversample, minimum=1)
        if not isinstance(use_range, (bool, np.bool_)):
            self._fail("use_range", use_range, "must be true or false")
        self.use_range = bool(use_range)
        self.min_range_km = check_positive(self, "min_range_km", min_range_km)
        self.max_range_km = check_positive(self, "max_range_km", max_range_km)
        if self.max_range_km <= self.min_range_km:
            self._fail("max_range_km", max_range_km, f"must be greater than min_range_km = {min_range_km}")
        self.max_range_rate_kms = check_positive(self, "max_range_rate_kms", max_range_rate_kms)
        self.max_speed_kms = check_positive(self, "max_speed_kms", max_speed_kms)

    def estimate(self, measurements: MeasurementSet, sensor: Sensor,
                 rng: np.random.Generator) -> ParticleCloud:
        """A cloud (N, 6) [LU, VU] at the epoch of the last measurement used."""
        names = list(measurements.names)
        angle_cols = [i for i, n in enumerate(names) if n != "range"]
        if len(angle_cols) != 2:
            raise IODError(f"{self._label()}: needs two angle components, got {names}")
        k = min(self.n_measurements, len(measurements))
        if k < 2:
            raise IODError(f"{self._label()}: needs at least 2 measurements of the first pass, got {len(measurements)}")
        i0, i1 = 0, k - 1
        t0, t1 = float(measurements.times[i0]), float(measurements.times[i1])
        dt = t1 - t0
        n = self.n_particles * self.oversample

        def los(i: int) -> np.ndarray:
            z = measurements.values[i, angle_cols] + measurements.sigmas[i, angle_cols] * rng.standard_normal((n, 2))
            return sensor.line_of_sight(z, np.full(n, measurements.times[i]))

        los0, los1 = los(i0), los(i1)
        lo, hi = float(units.km_to_lu(self.min_range_km)), float(units.km_to_lu(self.max_range_km))
        if self.use_range and "range" in names:
            j = names.index("range")
            rho1 = measurements.values[i1, j] + measurements.sigmas[i1, j] * rng.standard_normal(n)
        else:
            rho1 = rng.uniform(lo, hi, n)
        rdot = float(units.kms_to_vu(self.max_range_rate_kms)) * rng.uniform(-1.0, 1.0, n)
        rho0 = rho1 - rdot * dt
        p0 = sensor.observer_position(t0) + rho0[:, None] * los0
        p1 = sensor.observer_position(t1) + rho1[:, None] * los1
        v = (p1 - p0) / dt
        keep = ((rho0 >= lo) & (rho0 <= hi) & (rho1 >= lo) & (rho1 <= hi)
                & (np.linalg.norm(v, axis=1) <= float(units.kms_to_vu(self.max_speed_kms))))
        if keep.sum() < self.n_particles:
            raise IODError(f"{self._label()}: only {int(keep.sum())} of {n} samples survived the range and speed "
                           f"bounds (wanted {self.n_particles}); raise oversample")
        states = np.concatenate([p1, v], axis=1)[keep][: self.n_particles]
        return ParticleCloud(states, t1)
