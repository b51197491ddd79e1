"""The linear kinematic fit of the kinematic-fitting IOD: the measurements it uses, reduced to
arrays (:func:`prepare_fit`), and the synodic states of many sampled (angles, ranges) at once
(:func:`kinematic_states`). The IOD component that samples and prunes is in :mod:`.kinematic`;
Gauss's method (:mod:`.gauss`) reuses the same fit window.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.errors import IODError
from cistrack.interfaces import Sensor
from cistrack.model.measurement import MeasurementSet
from cistrack.units import ARCSEC_RAD

from .first_pass import first_pass_length, select_fit_indices
from .pass_screen import screen_pass
from .polyfit import evaluation_weights

__all__ = ["FitInputs", "FitWindow", "angle_names", "prepare_fit", "kinematic_states"]


class FitInputs:
    """The measurements a kinematic fit uses, validated and reduced to arrays.

    Attributes: ``indices`` (K,) into the measurement set, ``times`` (K,) TU, ``angles`` (K, 2)
    rad (azimuth, elevation; or the sensor's other angle pair, e.g. RA, Dec), ``angle_sigmas`` (K, 2) rad, ``ranges`` (K,) LU or None,
    ``observer`` (K, 3) LU synodic observer positions, ``weights`` (2, K) value/rate weights at
    the last time (rate per TU), ``screened``: the first pass's gross outliers left out, (index
    into the measurement set, angle rad off the other measurements' curve) (:mod:`.pass_screen`).
    """

    def __init__(self, indices, times, angles, angle_sigmas, ranges, observer, weights):
        self.indices = indices
        self.times = times
        self.angles = angles
        self.angle_sigmas = angle_sigmas
        self.ranges = ranges
        self.observer = observer
        self.weights = weights
        self.neu_to_synodic: np.ndarray | None = None
        self.screened: list[tuple[int, float]] = []  # first-pass gross outliers left out (index, offset rad)

    @property
    def epoch(self) -> float:
        return float(self.times[-1])

    def screened_record(self, measurements: MeasurementSet) -> list[dict]:
        """``screened`` as the cloud's ``meta["screened_out"]``: index, time (TU) and offset (arcsec)."""
        return [{"index": int(i), "t_tu": float(measurements.times[i]), "offset_arcsec": float(off / ARCSEC_RAD)}
                for i, off in self.screened]


def _column(ms: MeasurementSet, name: str, who: str) -> int:
    if name not in ms.names:
        raise IODError(f"{who}: the measurements have no '{name}' component "
                       f"(components: {', '.join(ms.names) or 'none'})")
    return ms.names.index(name)


def angle_names(sensor: Sensor) -> tuple[str, str]:
    """The sensor's two angle components: (azimuth, elevation), (right_ascension, declination), ...

    The fit only needs a longitude-like and a latitude-like angle of a unit vector,
    u = (cos b cos a, cos b sin a, sin b), in some observer frame (NEU for az/el, ICRF axes for
    RA/Dec) that the sensor's ``line_of_sight`` maps to synodic.
    """
    names = [n for n in getattr(sensor, "names", ()) if n != "range"]
    return (names[0], names[1]) if len(names) >= 2 else ("azimuth", "elevation")


@dataclass(frozen=True)
class FitWindow:
    """How the fitted measurements are chosen (:func:`.first_pass.select_fit_indices`).

    order : polynomial order of the fit; pass_gap_hours : a gap this long (hours) ends the first
    pass; fit_fraction : fraction of the first pass fitted; min_fit, max_fit : bounds on the
    number of fitted measurements.
    """

    order: int
    pass_gap_hours: float
    fit_fraction: float
    min_fit: int
    max_fit: int

    def select(self, times: np.ndarray) -> np.ndarray:
        """Indices into ``times`` (TU) of the fitted measurements."""
        return select_fit_indices(times, pass_gap_hours=self.pass_gap_hours, fit_fraction=self.fit_fraction,
                                  min_fit=self.min_fit, max_fit=self.max_fit, order=self.order)


def _measured_ranges(measurements: MeasurementSet, idx: np.ndarray, who: str) -> np.ndarray:
    """The measured ranges (K,) LU at ``idx``; raises IODError when there are none or one is <= 0."""
    if "range" not in measurements.names:
        raise IODError(f"{who}: the noisy-range model needs a measured 'range' component, "
                       f"but the measurements only have {', '.join(measurements.names)}; let "
                       f"the sensor measure range for IOD or use 'uniform-range'")
    ranges = measurements.values[idx][:, measurements.names.index("range")]
    if np.any(ranges <= 0):
        raise IODError(f"{who}: measured ranges must be > 0, but {int(np.sum(ranges <= 0))} of the {ranges.size} ranges "
                       "of the first pass are not (a range noise so large that ranges fall below zero: lower the "
                       "sensor's range_alpha, e.g. to 0.2 or less)")
    return ranges


def prepare_fit(measurements: MeasurementSet, sensor: Sensor, *, need_range: bool,
                who: str = "kinematic IOD", **window) -> FitInputs:
    """Select and validate the fitted measurements (raises IODError before any sampling).

    ``window``: the fields of :class:`FitWindow` by name (order, pass_gap_hours, fit_fraction,
    min_fit, max_fit). ``need_range``: also take the measured ranges (LU).
    """
    if not isinstance(measurements, MeasurementSet):
        raise IODError(f"{who}: expected a MeasurementSet, got {type(measurements).__name__}")
    win = FitWindow(**window)
    idx = win.select(measurements.times)
    first, second = angle_names(sensor)
    ia = _column(measurements, first, who)
    ie = _column(measurements, second, who)
    screened = _screened(measurements, sensor, ia, ie, win.pass_gap_hours, win.order,
                         max(win.min_fit, win.order + 1))
    if screened:  # the fit window chosen again without them (the same rule, the remaining times)
        rest = np.setdiff1d(np.arange(len(measurements)), [i for i, _ in screened])
        idx = rest[win.select(measurements.times[rest])]
    times = measurements.times[idx]
    angles = measurements.values[idx][:, [ia, ie]]
    sig = measurements.sigmas[idx][:, [ia, ie]]
    ranges = _measured_ranges(measurements, idx, who) if need_range else None
    observer = np.asarray(sensor.observer_position(times), dtype=float).reshape(len(idx), 3)
    weights = evaluation_weights(times, win.order, float(times[-1]))
    fit = FitInputs(idx, times, angles, sig, ranges, observer, weights)
    fit.neu_to_synodic = _neu_to_synodic(sensor, times, angles)
    fit.screened = screened
    return fit


def _screened(ms: MeasurementSet, sensor: Sensor, ia: int, ie: int, pass_gap_hours: float, order: int,
              need: int) -> list[tuple[int, float]]:
    """Gross outliers of the first pass (:func:`.pass_screen.screen_pass`): (index, offset rad)."""
    n = first_pass_length(ms.times, pass_gap_hours)
    ang = ms.values[:n][:, [ia, ie]]
    sig = ms.sigmas[:n][:, [ia, ie]]
    los = np.asarray(sensor.line_of_sight(ang, ms.times[:n]), dtype=float).reshape(n, 3)
    on_sky = np.maximum(sig[:, 0] * np.cos(ang[:, 1]), sig[:, 1])
    if not (np.all(np.isfinite(los)) and np.all(on_sky > 0)):
        return []
    return screen_pass(ms.times[:n], los, on_sky, order, need)


def _neu_to_synodic(sensor: Sensor, times: np.ndarray, angles: np.ndarray) -> np.ndarray | None:
    """Matrices M_k (K, 3, 3) with line_of_sight(az, el, t_k) = M_k @ u_neu(az, el), or None.

    An az/el sensor's line of sight is a rotation of the NEU unit vector; the columns of M_k are
    the lines of sight of North, East and Up. Checked against the sensor at the measured angles;
    a sensor whose angles are not NEU az/el falls back to calling line_of_sight per sample.
    """
    k = times.shape[0]
    basis = np.array([[0.0, 0.0], [0.5 * np.pi, 0.0], [0.0, 0.5 * np.pi]])   # N, E, Up
    ang = np.broadcast_to(basis, (k, 3, 2)).reshape(-1, 2)
    cols = np.asarray(sensor.line_of_sight(ang, np.repeat(times, 3)), dtype=float).reshape(k, 3, 3)
    m = np.swapaxes(cols, 1, 2)
    ce = np.cos(angles[:, 1])
    u = np.stack([ce * np.cos(angles[:, 0]), ce * np.sin(angles[:, 0]), np.sin(angles[:, 1])], axis=1)
    direct = np.asarray(sensor.line_of_sight(angles, times), dtype=float).reshape(k, 3)
    if np.max(np.abs(np.einsum("kij,kj->ki", m, u) - direct)) > 1e-12:
        return None
    return m


def kinematic_states(fit: FitInputs, sensor: Sensor, angles: np.ndarray,
                     rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fitted synodic states and topocentric velocities for sampled angles and ranges.

    Parameters
    ----------
    fit : FitInputs
    sensor : Sensor
    angles : (N, K, 2) rad, sampled azimuth/elevation at the fit times
    rho : (N, K) LU, sampled ranges

    Returns
    -------
    states : (N, 6) synodic state at ``fit.epoch`` (LU, VU)
    topo_velocity : (N, 3) VU, velocity of the polynomial fit of the NEU positions
        (Earth-fixed rotating frame, what the paper's 42 km/s bound refers to)
    """
    n, k = rho.shape
    # Layout (K, 6, N): the fit is then one (2, K) x (K, 6N) matrix product.
    az = angles[..., 0].T
    el = angles[..., 1].T
    r = rho.T
    data = np.empty((k, 6, n))  # filled in place: (K, N) temporaries cost more in page faults than in arithmetic
    rce = np.cos(el)
    rce *= r
    np.multiply(np.cos(az, out=data[:, 3]), rce, out=data[:, 3])
    np.multiply(np.sin(az, out=data[:, 4]), rce, out=data[:, 4])
    np.multiply(np.sin(el, out=data[:, 5]), r, out=data[:, 5])
    if fit.neu_to_synodic is not None:
        # los = M_k @ u_neu: one 3x3 matrix per fit time instead of one frame chain per sample
        np.matmul(fit.neu_to_synodic, data[:, 3:], out=data[:, :3])
        data[:, :3] += fit.observer[:, :, None]
    else:
        flat = angles.reshape(n * k, 2)
        tk = np.broadcast_to(fit.times, (n, k)).reshape(-1)
        los = np.asarray(sensor.line_of_sight(flat, tk), dtype=float).reshape(n, k, 3)
        data[:, :3] = fit.observer[:, :, None] + (rho[..., None] * los).transpose(1, 2, 0)
    out = (fit.weights @ data.reshape(k, 6 * n)).reshape(2, 6, n)
    states = np.concatenate([out[0, :3], out[1, :3]], axis=0).T.copy()
    return states, out[1, 3:].T.copy()
