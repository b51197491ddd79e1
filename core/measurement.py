"""Measurements: one observation and an ordered set of them."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import MeasurementError

__all__ = ["Measurement", "MeasurementSet"]


@dataclass(frozen=True)
class Measurement:
    """One observation.

    Attributes
    ----------
    t : float
        TU since the scenario epoch.
    z : (m,) float
        Measured values in the sensor's units (angles in rad, range in LU).
    covariance : (m, m) float
        Noise covariance of ``z``.
    names : tuple of str
        Name of each component of ``z`` (e.g. ("azimuth", "elevation")).
    index : int
        Position in its measurement set.
    """

    t: float
    z: np.ndarray
    covariance: np.ndarray
    names: tuple[str, ...]
    index: int = 0

    def angles_only(self) -> "Measurement":
        """This measurement without a 'range' component (IOD-only range is dropped for OD)."""
        keep = [i for i, n in enumerate(self.names) if n != "range"]
        return Measurement(self.t, self.z[keep], self.covariance[np.ix_(keep, keep)],
                           tuple(self.names[i] for i in keep), self.index)


@dataclass
class MeasurementSet:
    """Time-ordered measurements of one sensor.

    Attributes
    ----------
    times : (K,) float
        TU since the scenario epoch, strictly increasing.
    values : (K, m) float
        Measured values (rad, LU).
    sigmas : (K, m) float
        One-sigma noise of each value (rad, LU); noise is independent per component.
    names : tuple of str
        Component names, length m.
    """

    times: np.ndarray
    values: np.ndarray
    sigmas: np.ndarray
    names: tuple[str, ...]
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.times = np.asarray(self.times, dtype=float).reshape(-1)
        k = self.times.shape[0]
        m = len(self.names)
        self.values = np.asarray(self.values, dtype=float).reshape(k, m)
        self.sigmas = np.asarray(self.sigmas, dtype=float).reshape(k, m)
        if k and not np.all(np.isfinite(self.times)):
            raise MeasurementError("measurement times contain NaN or infinity")
        if k > 1 and np.any(np.diff(self.times) <= 0):
            i = int(np.argmax(np.diff(self.times) <= 0))
            raise MeasurementError(f"measurement times must increase strictly; row {i + 1} is not after row {i}")
        if not (np.all(np.isfinite(self.values)) and np.all(np.isfinite(self.sigmas))):
            raise MeasurementError("measurement values or sigmas contain NaN or infinity")
        if np.any(self.sigmas <= 0):
            raise MeasurementError("measurement sigmas must be > 0")

    def __len__(self) -> int:
        return self.times.shape[0]

    def __getitem__(self, i: int) -> Measurement:
        return Measurement(float(self.times[i]), self.values[i].copy(), np.diag(self.sigmas[i] ** 2),
                           self.names, int(i))

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def subset(self, mask_or_index) -> "MeasurementSet":
        """The measurements selected by a boolean mask or index array, in time order."""
        idx = np.arange(len(self))[mask_or_index]
        return MeasurementSet(self.times[idx], self.values[idx], self.sigmas[idx], self.names, dict(self.meta))

    def without(self, name: str) -> "MeasurementSet":
        """The set without component ``name`` (e.g. drop the IOD-only 'range')."""
        keep = [i for i, n in enumerate(self.names) if n != name]
        return MeasurementSet(self.times, self.values[:, keep], self.sigmas[:, keep],
                              tuple(self.names[i] for i in keep), dict(self.meta))
