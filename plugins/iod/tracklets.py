"""Tracklets and their attributables: what a telescope delivers, reduced to what ranging needs.

A **tracklet** is a run of observations of one site with no gap longer than ``gap_hours`` between
neighbours (survey cadence: 3-5 exposures over 10-30 minutes). Its **attributable** is the line of
sight and its rate at the tracklet's mean time, in the synodic frame of the sensor's
``line_of_sight``: the unit vectors of the observations are fitted by a straight line in time
(3 observations) or a parabola (4 or more) in time, by least squares: the observer's daily
circle bends a cislunar object's track by tens of arcseconds within half an hour, so a tracklet of
4 or more gets the curvature. With the observer's synodic position
and velocity at that time (from ``observer_position``, differenced over one minute), a range rho
and a range rate rho_dot give a full synodic state::

    r = o + rho u,    v = o_dot + rho_dot u + rho u_dot

Because every vector is synodic, ``v`` is the synodic velocity: no transport-theorem terms.
A tracklet whose observations miss their curve by more than :data:`MAX_MISFIT` sigma (a parabola
through 4 or more) or :data:`MAX_MISFIT_LINE` sigma (a line through 3, which cannot follow the
curvature) holds a gross outlier (or two objects) and is marked ``consistent = False``: ranging
starts from a consistent tracklet when there is one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.errors import IODError
from cistrack.interfaces import Sensor
from cistrack.model.measurement import MeasurementSet
from cistrack.units import hours_to_tu

__all__ = ["Attributable", "split_tracklets", "attributable", "states_from_ranges", "MAX_MISFIT",
           "MAX_MISFIT_LINE", "MAX_SPAN_HOURS"]

MAX_MISFIT = 10.0
"""Largest residual (sigma on the sky) from the parabola through a tracklet of 4 or more."""
MAX_MISFIT_LINE = 200.0
"""Largest residual (sigma on the sky) from the straight line through a tracklet of 3 (the
observer's motion alone bends 30 minutes of track by up to ~60 arcsec at 80,000 km)."""
MAX_SPAN_HOURS = 2.0
"""A tracklet is cut after this long, hours: a long pass becomes several tracklets."""
_DT_OBSERVER = 60.0 / 375_149.0  # one minute in TU: the observer's velocity by central differences


@dataclass(frozen=True)
class Attributable:
    """One tracklet reduced to its line of sight and rate.

    indices : (k,) int     rows of the measurement set
    site : str             the site's key ("" when the set names none)
    t : float              mean time, TU
    u, u_dot : (3,)        unit line of sight (synodic) and its rate per TU at ``t``
    observer, observer_dot : (3,)  observer position LU and velocity VU (synodic) at ``t``
    misfit : float         largest residual from the fitted curve, in sigma on the sky
    consistent : bool      misfit within :data:`MAX_MISFIT` (:data:`MAX_MISFIT_LINE` for 3)
    """

    indices: np.ndarray
    site: str
    t: float
    u: np.ndarray
    u_dot: np.ndarray
    observer: np.ndarray
    observer_dot: np.ndarray
    misfit: float
    consistent: bool


def split_tracklets(times, sites, gap_hours: float = 1.5,
                    max_span_hours: float = MAX_SPAN_HOURS) -> list[np.ndarray]:
    """Index arrays (each (k,) int, time order) of the tracklets of ``times`` (K,) TU, strictly
    increasing per site, and ``sites`` (K,) str (or None): a new tracklet starts after a gap longer
    than ``gap_hours``, where the site changes, or when it would last longer than
    ``max_span_hours``. Observations of two sites at interleaved times give one tracklet per site
    and stretch. Sorted by first time."""
    t = np.asarray(times, dtype=float).reshape(-1)
    s = np.asarray(sites, dtype=str).reshape(-1) if sites is not None else np.full(t.shape, "")
    if t.shape != s.shape:
        raise IODError(f"tracklets: {t.shape[0]} times but {s.shape[0]} sites")
    gap = float(hours_to_tu(gap_hours))
    span = float(hours_to_tu(max_span_hours))
    out: list[list[int]] = []
    last: dict[str, int] = {}  # site -> index into out of its open tracklet
    for i in range(t.shape[0]):
        j = last.get(s[i])
        if j is not None and t[i] - t[out[j][-1]] <= gap and t[i] - t[out[j][0]] <= span:
            out[j].append(i)
        else:
            last[s[i]] = len(out)
            out.append([i])
    return [np.asarray(o, dtype=int) for o in sorted(out, key=lambda o: t[o[0]])]


def _line_of_sight(ms: MeasurementSet, sensor: Sensor, idx: np.ndarray) -> np.ndarray:
    """Synodic unit lines of sight (k, 3) of the rows ``idx`` of one site (the first two
    components: the angles), in one call of that site's sensor."""
    s = sensor.for_measurement(ms[int(idx[0])])
    out = np.asarray(s.line_of_sight(np.asarray(ms.values[idx, :2], dtype=float), ms.times[idx]),
                     dtype=float).reshape(idx.size, 3)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _observer(ms: MeasurementSet, sensor: Sensor, i: int, t: float) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,) LU, velocity (3,) VU) of the observer of row ``i`` at ``t`` TU."""
    s = sensor.for_measurement(ms[i])
    tt = np.array([t - _DT_OBSERVER, t, t + _DT_OBSERVER])
    o = np.asarray(s.observer_position(tt), dtype=float).reshape(3, 3)
    return o[1], (o[2] - o[0]) / (2.0 * _DT_OBSERVER)


def attributable(ms: MeasurementSet, sensor: Sensor, idx) -> Attributable:
    """The :class:`Attributable` of the tracklet of rows ``idx`` (k >= 2) of ``ms`` (angles rad,
    sigmas rad; RA's sigma is RA's own, i.e. on the sky divided by cos(Dec))."""
    idx = np.asarray(idx, dtype=int).reshape(-1)
    if idx.size < 2:
        raise IODError(f"tracklet of {idx.size} observation(s): an attributable needs at least 2")
    t = ms.times[idx]
    tm = float(np.mean(t))
    u = _line_of_sight(ms, sensor, idx)
    dt = t - tm
    a = np.stack([np.ones_like(t), dt, dt * dt], axis=1)[:, :3 if idx.size >= 4 else 2]
    coef, *_ = np.linalg.lstsq(a, u, rcond=None)
    resid = np.linalg.norm(u - a @ coef, axis=1)              # rad, on the sky
    sig = ms.sigmas[idx][:, :2]
    on_sky = np.maximum(np.maximum(sig[:, 0] * np.cos(ms.values[idx, 1]), sig[:, 1]), 1e-12)
    misfit = float(np.max(resid / on_sky)) if idx.size > a.shape[1] else 0.0
    limit = MAX_MISFIT if a.shape[1] == 3 else MAX_MISFIT_LINE
    u0 = coef[0] / np.linalg.norm(coef[0])
    u_dot = coef[1] - u0 * float(u0 @ coef[1])                # keep |u| = 1 to first order
    o, o_dot = _observer(ms, sensor, int(idx[0]), tm)
    return Attributable(idx, ms.site_at(int(idx[0])), tm, u0, u_dot, o, o_dot, misfit, misfit <= limit)


def states_from_ranges(att: Attributable, rho, rho_dot) -> np.ndarray:
    """Synodic states (N, 6) LU, VU at ``att.t`` for ranges ``rho`` (N,) LU and range rates
    ``rho_dot`` (N,) VU."""
    rho = np.asarray(rho, dtype=float).reshape(-1)
    rd = np.asarray(rho_dot, dtype=float).reshape(-1)
    r = att.observer[None] + rho[:, None] * att.u[None]
    v = att.observer_dot[None] + rd[:, None] * att.u[None] + rho[:, None] * att.u_dot[None]
    return np.concatenate([r, v], axis=1)
