"""The measured components of one measurement, seen from a filter.

A run may hand a filter fewer components than its sensor measures (the IOD-only 'range' is
stripped for OD). :class:`MeasuredComponents` selects the sensor's output columns by name,
validates z and R, and gives predictions and angle-wrapped residuals for just those columns. For
a :class:`cistrack.model.measurement.StackedMeasurement` (several sites at one time) it stacks the
parts: each predicted from its own site, R block-diagonal; a filter using only ``z``, ``R`` and
these methods updates on the stack in one step (``stacked_updates = True``).
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError, MeasurementError
from cistrack.interfaces import Sensor
from cistrack.model.measurement import Measurement, StackedMeasurement

__all__ = ["MeasuredComponents", "check_epoch", "EPOCH_TOLERANCE_TU"]

EPOCH_TOLERANCE_TU = 1e-9
"""A measurement within this many TU of the belief's epoch counts as taken at that epoch."""


def check_epoch(epoch: float, measurement: Measurement, who: str) -> None:
    """Raise FilterError unless ``measurement`` is a Measurement taken at the belief's ``epoch`` (TU)."""
    if not isinstance(measurement, (Measurement, StackedMeasurement)):
        raise FilterError(f"filter '{who}': update() needs a cistrack Measurement, got {type(measurement).__name__}")
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
        parts = getattr(measurement, "parts", None)
        self._parts: list[MeasuredComponents] | None = None
        if parts is not None:  # a cistrack.model.measurement.StackedMeasurement: several sites at one time
            self._stack(sensor, measurement, parts)
            return
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

    def _stack(self, sensor: Sensor, measurement, parts) -> None:
        """The parts' components stacked: z and the columns one after the other, R block-diagonal,
        each part predicted by the sensor of its own site."""
        self._parts = [MeasuredComponents(sensor, p) for p in parts]
        self.sensor = sensor
        self.cols = np.concatenate([p.cols for p in self._parts])
        self.z = np.concatenate([p.z for p in self._parts])
        self.R = np.asarray(measurement.covariance, dtype=float)
        self.angular = np.concatenate([p.angular for p in self._parts])
        self.t = float(measurement.t)
        self._cuts = np.cumsum([p.dim for p in self._parts])[:-1]

    def _each(self, method: str, *arrays) -> np.ndarray:
        """``method`` of every part on its own columns of ``arrays`` (last axis), stacked."""
        split = [np.split(np.asarray(a, dtype=float), self._cuts, axis=-1) for a in arrays]
        return np.concatenate([getattr(p, method)(*(s[k] for s in split)) for k, p in enumerate(self._parts)],
                              axis=-1)

    @property
    def dim(self) -> int:
        return int(self.cols.size)

    def predict(self, states: np.ndarray) -> np.ndarray:
        """Noise-free predicted measurements h(x) of ``states`` (N, 6) -> (N, m): one sensor call."""
        if self._parts is not None:
            return np.concatenate([p.predict(states) for p in self._parts], axis=-1)
        return np.asarray(self.sensor.measure(states, self.t), dtype=float)[:, self.cols]

    def residual(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a - b (..., m) with the sensor's wrapping of angular columns (via ``sensor.residual``)."""
        if self._parts is not None:
            b = np.broadcast_to(np.asarray(b, dtype=float), np.shape(a))
            return self._each("residual", a, b)
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
        if self._parts is not None:
            return np.concatenate([p.residuals_to_measurement(states) for p in self._parts], axis=-1)
        return self.residual(self.predict(states), self.z)

    def mean(self, zs: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """Weighted mean of predicted measurements ``zs`` (K, m) with ``weights`` (K,), circular
        (atan2 of weighted sines and cosines) on the angular columns, wrapped to [0, 2pi)."""
        if self._parts is not None:
            split = np.split(np.asarray(zs, dtype=float), self._cuts, axis=-1)
            return np.concatenate([p.mean(z, weights) for p, z in zip(self._parts, split)])
        zs = np.asarray(zs, dtype=float)
        w = np.asarray(weights, dtype=float)
        out = w @ zs
        if self.angular.any():
            a = zs[:, self.angular]
            out[self.angular] = np.arctan2(w @ np.sin(a), w @ np.cos(a)) % (2.0 * np.pi)
        return out
