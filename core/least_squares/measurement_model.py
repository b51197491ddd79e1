"""The measurement model of the fit: predicted measurements, residuals and their Jacobian.

Each row of a :class:`cistrack.model.measurement.MeasurementSet` is predicted by the sensor that
took it (``sensor.for_measurement``: the site's own sensor in a multi-site set). Components named
"range" (the IOD-only range of a simulated sensor) are left out unless asked for. The sensor's
components must line up with the set's: the set's column j is the sensor's column j.

Jacobian H = d h / d x (K, m, 6): from the sensor's optional ``measurement_jacobian(states (N, 6),
t) -> (N, m, 6)`` when it has one, else by central differences of ``measure`` (angle differences
wrapped), all rows of a site in one call.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.errors import MeasurementError
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet, kind_of_names

__all__ = ["MeasurementModel", "DEFAULT_SENSOR_STEPS"]

DEFAULT_SENSOR_STEPS: np.ndarray = np.array([1e-7, 1e-7, 1e-7, 1e-5, 1e-5, 1e-5])
"""Central-difference steps of the measurement Jacobian: 1e-7 LU (38 m) in position, 1e-5 VU
(1 cm/s) in velocity (angles depend on velocity only through light time and aberration)."""


def _wrap(r: np.ndarray, angular: np.ndarray) -> np.ndarray:
    r = np.array(r, dtype=float, copy=True)
    if angular.any():
        r[..., angular] = (r[..., angular] + np.pi) % (2.0 * np.pi) - np.pi
    return r


class MeasurementModel:
    """Predicts the used components of every row of ``measurements`` from states at their times.

    Parameters
    ----------
    sensor : Sensor
        The sensor (or site network) that took the measurements.
    measurements : MeasurementSet
        K rows of m_set components (rad, LU).
    use_range : bool
        Fit the components named "range" too (default: angles only).
    steps : (6,) float, optional
        Central-difference steps (LU, VU) of the Jacobian; default :data:`DEFAULT_SENSOR_STEPS`.

    Attributes
    ----------
    columns : (m,) int        the set's columns that are fitted
    names : tuple of str      their names
    angular : (m,) bool       which of them wrap at ±pi
    values, sigmas : (K, m)   the measured values and their one-sigma noise (rad, LU)
    """

    def __init__(self, sensor: Sensor, measurements: MeasurementSet, use_range: bool = False,
                 steps: Any = None) -> None:
        if not isinstance(measurements, MeasurementSet):
            raise MeasurementError(f"the fit needs a MeasurementSet, got {type(measurements).__name__}")
        if len(measurements) == 0:
            raise MeasurementError("the fit needs at least one measurement; the set is empty")
        s_names = tuple(getattr(sensor, "names", ()))
        m_names = tuple(measurements.names)
        if len(s_names) < len(m_names):
            raise MeasurementError(f"the sensor measures {s_names} but the measurements have {len(m_names)} "
                                   f"components {m_names}")
        mixed = not kind_of_names(m_names) and m_names[:2] == ("angle_1", "angle_2")
        for j, name in enumerate(m_names):
            if not (mixed and j < 2) and s_names[j] != name:
                raise MeasurementError(f"measurement component {j} is {name!r} but the sensor's is "
                                       f"{s_names[j]!r}; fit with the sensor that took the measurements "
                                       f"(sensor components {s_names}, measurement components {m_names})")
        self.columns = np.array([j for j, n in enumerate(m_names) if use_range or n != "range"], dtype=int)
        if self.columns.size == 0:
            raise MeasurementError(f"no component to fit among {m_names} (only a range, and use_range is off)")
        self.sensor = sensor
        self.measurements = measurements
        self.names = tuple(m_names[j] for j in self.columns)
        flags = tuple(getattr(sensor, "angular", ())) or (False,) * len(s_names)
        self.angular = np.array([bool(flags[j]) for j in self.columns])
        self._full = self.columns.size == len(s_names)
        self.values = measurements.values[:, self.columns]
        self.sigmas = measurements.sigmas[:, self.columns]
        self.times = measurements.times
        self.steps = DEFAULT_SENSOR_STEPS if steps is None else np.asarray(steps, dtype=float).reshape(6)
        self._groups: list[tuple[Sensor, np.ndarray]] = []
        for key in measurements.site_keys():
            rows = (np.arange(len(measurements)) if measurements.sites is None
                    else np.nonzero(measurements.sites == key)[0])
            own = sensor.for_measurement(measurements[int(rows[0])]) if hasattr(sensor, "for_measurement") else sensor
            self._groups.append((own, rows))

    @property
    def m(self) -> int:
        """Number of fitted components per row."""
        return int(self.columns.size)

    def _measure(self, sensor: Sensor, states: np.ndarray, t: np.ndarray) -> np.ndarray:
        z = np.asarray(sensor.measure(states, t), dtype=float)
        if z.ndim != 2 or z.shape[0] != states.shape[0]:
            raise MeasurementError(f"sensor {type(sensor).__name__}.measure returned shape {z.shape} for "
                                   f"{states.shape[0]} states")
        z = z[:, self.columns]
        if not np.all(np.isfinite(z)):
            raise MeasurementError(f"sensor {type(sensor).__name__} predicted NaN or infinite measurements "
                                   f"for the fitted trajectory")
        return z

    def predict(self, states: np.ndarray) -> np.ndarray:
        """Predicted measurements (K, m) for the states (K, 6) at the K measurement times."""
        out = np.empty((states.shape[0], self.m))
        for sensor, rows in self._groups:
            out[rows] = self._measure(sensor, states[rows], self.times[rows])
        return out

    def residuals(self, states: np.ndarray) -> np.ndarray:
        """Observed minus computed (K, m), angles wrapped into [-pi, pi)."""
        zhat = self.predict(states)
        if self._full:
            return np.asarray(self.sensor.residual(self.values, zhat), dtype=float)
        return _wrap(self.values - zhat, self.angular)

    def jacobian(self, states: np.ndarray) -> np.ndarray:
        """d h / d x (K, m, 6) at the states (K, 6)."""
        out = np.empty((states.shape[0], self.m, 6))
        for sensor, rows in self._groups:
            x = states[rows]
            t = self.times[rows]
            analytic = getattr(sensor, "measurement_jacobian", None)
            if callable(analytic):
                jac = np.asarray(analytic(x, t), dtype=float)
                if jac.ndim != 3 or jac.shape[0] != rows.size or jac.shape[2] != 6:
                    raise MeasurementError(f"sensor {type(sensor).__name__}.measurement_jacobian returned "
                                           f"shape {jac.shape}; expected ({rows.size}, m, 6)")
                out[rows] = jac[:, self.columns, :]
                continue
            n = rows.size
            pert = np.repeat(x[:, None, :], 12, axis=1)            # (n, 12, 6)
            for j in range(6):
                pert[:, 2 * j, j] += self.steps[j]
                pert[:, 2 * j + 1, j] -= self.steps[j]
            z = self._measure(sensor, pert.reshape(-1, 6), np.repeat(t, 12)).reshape(n, 12, self.m)
            diff = _wrap(z[:, 0::2, :] - z[:, 1::2, :], self.angular)  # (n, 6, m)
            out[rows] = np.transpose(diff / (2.0 * self.steps[None, :, None]), (0, 2, 1))
        if not np.all(np.isfinite(out)):
            raise MeasurementError("the measurement Jacobian is not finite (a state at the observer?)")
        return out
