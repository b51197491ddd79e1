"""The measured components of one measurement, seen from a filter.

A run may hand a filter fewer components than its sensor measures (the IOD-only 'range' is
stripped for OD). :class:`MeasuredComponents` selects the sensor's output columns by name,
validates z and R, and gives predictions and angle-wrapped residuals for just those columns.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError, MeasurementError
from cistrack.interfaces import Sensor
from cistrack.measurement import Measurement

__all__ = ["MeasuredComponents", "check_epoch", "EPOCH_TOLERANCE_TU"]

EPOCH_TOLERANCE_TU = 1e-9
"""A measurement within this many TU of the belief's epoch counts as taken at that epoch."""


def check_epoch(epoch: float, measurement: Measurement, who: str) -> None:
    """Raise FilterError unless ``measurement`` was taken at the belief's ``epoch`` (TU)."""
    if abs(float(measurement.t) - float(epoch)) > EPOCH_TOLERANCE_TU * max(1.0, abs(float(epoch))):
        raise FilterError(f"filter '{who}': measurement at t = {measurement.t!r} TU but the belief is at "
                          f"t = {epoch!r} TU; call predict(measurement.t) before update()")


class MeasuredComponents:
    """The sensor columns present in ``measurement``.

    Attributes
    ----------
    cols : (m,) int      indices into ``sensor.names``
    z : (m,) float       measured values (rad, LU)
    R : (m, m) float     noise covariance, positive definite
    angular : (m,) bool  which columns wrap at ±pi
    t : float            measurement time, TU
    """

    def __init__(self, sensor: Sensor, measurement: Measurement):
        # a sensor standing for several sites answers with the one that took the measurement
        sensor = sensor.for_measurement(measurement) if hasattr(sensor, "for_measurement") else sensor
        names = tuple(sensor.names)
        unknown = [n for n in measurement.names if n not in names]
        if unknown:
            raise MeasurementError(f"measurement components {unknown} are not measured by sensor "
                                   f"'{sensor.registry_name or type(sensor).__name__}' (it measures {list(names)})")
        if len(set(measurement.names)) != len(measurement.names) or not measurement.names:
            raise MeasurementError(f"measurement component names {measurement.names} must be non-empty and unique")
        self.sensor = sensor
        self.cols = np.array([names.index(n) for n in measurement.names], dtype=np.intp)
        m = self.cols.size
        self.z = np.asarray(measurement.z, dtype=float).reshape(-1)
        self.R = np.asarray(measurement.covariance, dtype=float)
        if self.z.shape != (m,) or self.R.shape != (m, m):
            raise MeasurementError(f"measurement has {m} names but z of shape {self.z.shape} and covariance of "
                                   f"shape {self.R.shape}")
        if not (np.all(np.isfinite(self.z)) and np.all(np.isfinite(self.R))):
            raise MeasurementError("measurement value or covariance contains NaN or infinity")
        try:
            np.linalg.cholesky(0.5 * (self.R + self.R.T))
        except np.linalg.LinAlgError:
            raise MeasurementError(f"measurement covariance is not positive definite: {self.R.tolist()}") from None
        ang = np.asarray(sensor.angular, dtype=bool)
        self.angular = ang[self.cols] if ang.size == len(names) else np.zeros(m, dtype=bool)
        self.t = float(measurement.t)
        self._width = len(names)

    @property
    def dim(self) -> int:
        return int(self.cols.size)

    def predict(self, states: np.ndarray) -> np.ndarray:
        """Noise-free predicted measurements h(x) of ``states`` (N, 6) -> (N, m): one sensor call."""
        return np.asarray(self.sensor.measure(states, self.t), dtype=float)[:, self.cols]

    def residual(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a - b (..., m) with the sensor's wrapping of angular columns (via ``sensor.residual``)."""
        a = np.asarray(a, dtype=float)
        b = np.broadcast_to(np.asarray(b, dtype=float), a.shape)
        shape = a.shape[:-1] + (self._width,)
        fa = np.zeros(shape)
        fb = np.zeros(shape)
        fa[..., self.cols] = a
        fb[..., self.cols] = b
        return np.asarray(self.sensor.residual(fa, fb), dtype=float)[..., self.cols]

    def residuals_to_measurement(self, states: np.ndarray) -> np.ndarray:
        """h(x) - z for ``states`` (N, 6) -> (N, m), angles wrapped: the predictions expressed in a
        chart centred on the measurement, so means and covariances never straddle the 0/2pi cut."""
        return self.residual(self.predict(states), self.z)

    def mean(self, zs: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """Weighted mean of predicted measurements ``zs`` (K, m) with ``weights`` (K,), circular
        (atan2 of weighted sines and cosines) on the angular columns, wrapped to [0, 2pi)."""
        zs = np.asarray(zs, dtype=float)
        w = np.asarray(weights, dtype=float)
        out = w @ zs
        if self.angular.any():
            a = zs[:, self.angular]
            out[self.angular] = np.arctan2(w @ np.sin(a), w @ np.cos(a)) % (2.0 * np.pi)
        return out
