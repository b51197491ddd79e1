"""Impacts and closest approaches of a fitted orbit, with their 1-sigma by linear mapping.

An **impact** is the dynamics' own: :meth:`Dynamics.propagate` stops a particle on a body's
surface and reports the body and the time (:class:`cistrack.interfaces.dynamics.Propagation`);
the impact point is the state it is frozen at. A **closest approach** is a local minimum of the
distance to the Moon's or the Earth's centre before the span's end (or an impact): the distance
is sampled every :data:`APPROACH_STEP_MINUTES`, each interior minimum is refined on a grid of at most 10 s
(its time where the radial velocity changes sign, linearly interpolated; its state by cubic
Hermite interpolation). A **descent through an altitude** (``altitude=("Moon", 100.0)``, kind
"altitude 100 km") is the first time the distance to the body's centre falls to its impact radius
plus that altitude: found on a 10-minute grid, refined on one of at most 10 s, interpolated.

Each event carries: the time (TU since the dynamics' epoch, and UTC), the body, the latitude and
longitude of the point (impact point or sub-orbit point at the approach): selenographic in the
Moon's mean-Earth frame (DE421 librations, :mod:`.body_fixed`) or geodetic (WGS84), the altitude
above the body's impact sphere (km; 0 at an impact) and the speed relative to the body's centre
(km/s, inertial; the Moon's surface turns at 4.6 m/s, the Earth's at up to 0.47 km/s). Positions
relative to the bodies come from the dynamics' real Earth-Moon frame (``dynamics.frame``, the
``ephemeris`` model); for a model without one (``cr3bp``) they are taken in the synodic frame with
the bodies where :meth:`Body.position_at` puts them, and there are no latitudes and longitudes.

The 1-sigma of each quantity is the linear map of the covariance: the event recomputed for the
12 states ``x0 +- eps s_i`` (``s_i`` the columns of a square root of the covariance,
``eps = EPS_SIGMA``), central differences ``g_i`` per unit sigma, and
``cov(event) = sum_i g_i g_i^T``. tests/fit/test_orbit_events.py checks it against 200 states
drawn from the covariance.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import StateError
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["OrbitEvent", "orbit_events", "event_values", "first_impact", "times_until_impact", "EVENT_FIELDS",
           "EPS_SIGMA", "IMPACT_MARGIN_S", "fit_events", "FIT_EVENT_DAYS",
           "prediction_end", "altitude_kind", "event_lines"]

EVENT_FIELDS = ("t_tu", "latitude_deg", "longitude_deg", "altitude_km", "speed_kms")
"""The columns of :func:`event_values`."""
EPS_SIGMA = 0.05
"""Step of the central differences of the linear mapping, in sigmas of the covariance."""
_FINE_S = 10.0
APPROACH_STEP_MINUTES = 10.0
"""Spacing of the grid on which distance minima (closest approaches) are first looked for."""
FIT_EVENT_DAYS = 14.0
"""Days after a fit's epoch over which :func:`fit_events` looks for impacts and closest approaches."""
IMPACT_MARGIN_S = 1e-3
"""A prediction that ends at an impact ends this long before it, seconds (the state at the impact
time itself is on the surface, where the dynamics stop it)."""


@dataclass(frozen=True)
class OrbitEvent:
    """One impact or closest approach (see the module docstring).

    ``sigma`` holds the 1-sigma of ``time_s`` (s), ``latitude_deg``, ``longitude_deg``,
    ``altitude_km`` and ``speed_kms``; NaN where the mapping could not be made (a neighbouring
    orbit of the covariance has no such event)."""

    kind: str
    body: str
    t_tu: float
    utc: str
    latitude_deg: float
    longitude_deg: float
    altitude_km: float
    speed_kms: float
    coordinates: str
    sigma: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready fields (NaN as None)."""
        def clean(v):
            return None if isinstance(v, float) and not np.isfinite(v) else v
        out = {k: clean(getattr(self, k)) for k in ("kind", "body", "t_tu", "utc", "latitude_deg", "longitude_deg",
                                                    "altitude_km", "speed_kms", "coordinates")}
        out["sigma"] = {k: clean(float(v)) for k, v in self.sigma.items()}
        return out

    def _pm(self, key: str, fmt: str) -> str:
        """`` +- sigma`` of ``key`` in format ``fmt``, or "" without sigmas."""
        v = self.sigma.get(key)
        return "" if v is None else f" +- {v:{fmt}}" if np.isfinite(v) else " +- ?"

    def lines(self) -> list[str]:
        """Printed lines (each under 120 columns): what, when, how high and how fast; then where."""
        alt = "" if self.kind == "impact" else f", altitude {self.altitude_km:.6g}{self._pm('altitude_km', '.2g')} km"
        when = f"{self.utc[:19]}Z" + (f"{self._pm('time_s', '.3g')} s" if self.sigma else "")
        out = [f"{self.kind} ({self.body}) {when}{alt}, speed "
               f"{self.speed_kms:.4f}{self._pm('speed_kms', '.2g')} km/s"]
        if np.isfinite(self.latitude_deg):
            out.append(f"  {self.coordinates} latitude {self.latitude_deg:.3f}{self._pm('latitude_deg', '.2g')} deg, "
                       f"longitude {self.longitude_deg:.3f}{self._pm('longitude_deg', '.2g')} deg"
                       + (" (1-sigma)" if self.sigma else ""))
        if self.undetermined():
            out.append(UNDETERMINED_NOTE)
        return out

    def undetermined(self) -> bool:
        """Whether a 1-sigma could not be mapped (printed ``+- ?``)."""
        return any(not np.isfinite(v) for v in self.sigma.values())


UNDETERMINED_NOTE = ("  (? : no 1-sigma: varied within its covariance the orbit has no such event in the search "
                     "window, so the event is poorly determined)")
"""What a printed ``+- ?`` means (said once under a list of events)."""


def _epoch_of(dynamics: Dynamics, epoch: datetime | str | None) -> datetime | None:
    if epoch is not None:
        return units.parse_utc(epoch)
    e = getattr(dynamics, "epoch", None)
    return units.parse_utc(e) if isinstance(e, str) else None


def _body_index(dynamics: Dynamics, body: str) -> int:
    names = [b.name.lower() for b in dynamics.bodies]
    if body.lower() not in names:
        raise StateError(f"events: the dynamics have no impact body {body!r}; bodies: "
                         + (", ".join(b.name for b in dynamics.bodies) or "none"))
    return names.index(body.lower())


def _relative(dynamics: Dynamics, x: np.ndarray, t: np.ndarray, body: str):
    """Body-centred positions (N, 3) km, velocities (N, 3) km/s (GCRS axes where the dynamics
    have a real Earth-Moon frame, else synodic) and the TDB dates (jd1, jd2) (or None)."""
    frame = getattr(dynamics, "frame", None)
    if frame is None or not hasattr(frame, "synodic_to_gcrs"):
        b = dynamics.bodies[_body_index(dynamics, body)]
        centre = np.array([b.position_at(ti) for ti in t]).reshape(-1, 3)
        return (x[:, :3] - centre) * units.LU_KM, x[:, 3:] * units.VU_KMS, None
    g = frame.synodic_to_gcrs(x, t, unit="km")
    jd = (np.full(t.size, frame.epoch_tdb[0]), frame.epoch_tdb[1] + frame.tdb_days(t))
    if body.lower() == "earth":
        return g[:, :3], g[:, 3:], jd
    r, v = frame.ephemeris.moon(*jd)
    return g[:, :3] - r, g[:, 3:] - v, jd


def _describe(dynamics: Dynamics, x: np.ndarray, t: np.ndarray, body: str, epoch: datetime | None) -> np.ndarray:
    """(N, 5) event values (:data:`EVENT_FIELDS`) of the states ``x`` (N, 6) at ``t`` (N,) TU."""
    from cistrack.least_squares.body_fixed import geodetic, selenographic

    out = np.full((x.shape[0], 5), np.nan)
    if x.shape[0] == 0:
        return out
    r, v, jd = _relative(dynamics, x, t, body)
    radius = dynamics.bodies[_body_index(dynamics, body)].radius * units.LU_KM
    out[:, 0] = t
    out[:, 3] = np.linalg.norm(r, axis=1) - radius
    out[:, 4] = np.linalg.norm(v, axis=1)
    if jd is not None and body.lower() == "moon":
        out[:, 1], out[:, 2] = selenographic(r, *jd)
    elif jd is not None and epoch is not None:
        out[:, 1], out[:, 2], _ = geodetic(r, epoch, t * units.TU_S)
    return out


def _impact_values(dynamics: Dynamics, x: np.ndarray, t0: float, t_end: float, body: str,
                   epoch: datetime | None) -> np.ndarray:
    prop = dynamics.propagate(x, t0, np.array([t_end]))
    hit = (~np.asarray(prop.alive)) & (np.asarray(prop.impact_body) == _body_index(dynamics, body))
    out = np.full((x.shape[0], 5), np.nan)
    t = np.asarray(prop.impact_time, dtype=float)[hit]
    out[hit] = _describe(dynamics, np.asarray(prop.states)[-1][hit], t, body, epoch)
    out[hit, 3] = 0.0
    return out


def _distances(dynamics: Dynamics, states: np.ndarray, grid: np.ndarray, body: str):
    """Body-centred (K, N, 3) positions km and velocities km/s of ``states`` (K, N, 6) on ``grid`` (K,)."""
    k, n = states.shape[:2]
    r, v, _ = _relative(dynamics, states.reshape(-1, 6), np.repeat(grid, n), body)
    return r.reshape(k, n, 3), v.reshape(k, n, 3)


def _approach_values(dynamics: Dynamics, x: np.ndarray, t0: float, window: tuple[float, float], body: str,
                     epoch: datetime | None) -> np.ndarray:
    """(N, 5) values of the closest approach of each state ``x`` (N, 6) to ``body`` within
    ``window`` (TU, after ``t0``); NaN rows where the distance has no interior minimum there."""
    lo, hi = window
    n_fine = int(min(4000, max(50, np.ceil((hi - lo) * units.TU_S / _FINE_S))))
    grid = np.linspace(lo, hi, n_fine)
    prop = dynamics.propagate(x, t0, grid)
    states = np.asarray(prop.states, dtype=float)
    r, v = _distances(dynamics, states, grid, body)
    radial = np.sum(r * v, axis=2)                                   # (K, N): d/dt |r|^2 / 2
    alive = grid[:, None] < np.asarray(prop.impact_time, dtype=float)[None, :]
    out = np.full((x.shape[0], 5), np.nan)
    for j in range(x.shape[0]):                                      # a few particles; arrays inside
        ok = np.flatnonzero((radial[:-1, j] < 0) & (radial[1:, j] >= 0) & alive[1:, j])
        if ok.size == 0:
            continue
        k = ok[np.argmin(np.linalg.norm(r[ok, j], axis=1))]
        f = radial[k, j] / (radial[k, j] - radial[k + 1, j])
        out[j] = _interpolated(dynamics, states[k:k + 2, j], grid[k:k + 2], f, body, epoch)
    return out


def _interpolated(dynamics: Dynamics, pair: np.ndarray, tt: np.ndarray, f: float, body: str,
                  epoch: datetime | None) -> np.ndarray:
    """Event values at the fraction ``f`` between two states ``pair`` (2, 6) at ``tt`` (2,): the
    position and the velocity by cubic Hermite interpolation (synodic; with the velocities and
    the dynamics' accelerations)."""
    h = (tt[1] - tt[0])
    h00, h10, h01, h11 = 2 * f ** 3 - 3 * f ** 2 + 1, f ** 3 - 2 * f ** 2 + f, -2 * f ** 3 + 3 * f ** 2, f ** 3 - f ** 2
    acc = np.array([dynamics.derivatives(float(tt[i]), pair[i:i + 1])[0, 3:] for i in (0, 1)])
    x = np.empty(6)
    x[:3] = h00 * pair[0, :3] + h10 * h * pair[0, 3:] + h01 * pair[1, :3] + h11 * h * pair[1, 3:]
    x[3:] = h00 * pair[0, 3:] + h10 * h * acc[0] + h01 * pair[1, 3:] + h11 * h * acc[1]
    t = tt[0] + f * h
    return _describe(dynamics, x[None], np.array([t]), body, epoch)[0]


def altitude_kind(altitude_km: float) -> str:
    """The event kind of a descent through ``altitude_km`` (> 0) above a body's impact sphere."""
    if not (isinstance(altitude_km, (int, float)) and np.isfinite(altitude_km) and altitude_km > 0):
        raise StateError(f"events: altitude {altitude_km!r} km must be a number > 0 (above the impact sphere)")
    return f"altitude {float(altitude_km):g} km"


def _first_below(distance: np.ndarray) -> np.ndarray:
    """Index (N,) of the first sample (of K, axis 0) at or below 0 after one above it, -1 for none."""
    below = distance <= 0
    first = np.where(below.any(axis=0), np.argmax(below, axis=0), -1)
    return np.where(first > 0, first, -1)


def _crossing_values(dynamics: Dynamics, x: np.ndarray, t0: float, window: tuple[float, float], body: str,
                     altitude_km: float, epoch: datetime | None) -> np.ndarray:
    """(N, 5) values where each state ``x`` (N, 6) first descends through ``altitude_km`` above
    ``body``'s impact sphere within ``window`` (TU): found on a 10-minute grid, refined on one of
    at most 10 s, interpolated; NaN rows where it does not."""
    out = np.full((x.shape[0], 5), np.nan)
    lo, hi = max(window[0], t0 + 1e-12), window[1]
    grid = np.linspace(lo, hi, max(3, int(np.ceil((hi - lo) * units.TU_S / 600.0)) + 1))
    for fine in (False, True):
        prop = dynamics.propagate(x, t0, grid)
        states = np.asarray(prop.states, dtype=float)
        r, _v = _distances(dynamics, states, grid, body)
        radius = dynamics.bodies[_body_index(dynamics, body)].radius * units.LU_KM
        d = np.linalg.norm(r, axis=2) - radius - altitude_km
        k = _first_below(d)                                         # an orbit stopped on the surface is below
        if not np.any(k > 0):
            return out
        if fine:
            break
        lo, hi = grid[np.min(k[k > 0]) - 1], grid[np.max(k[k > 0])]
        grid = np.linspace(lo, hi, int(min(4000, max(50, np.ceil((hi - lo) * units.TU_S / _FINE_S)))))
    for j in np.flatnonzero(k > 0):
        i = k[j]
        slope = d[i - 1, j] - d[i, j]                               # km per unit fraction of the interval
        f = d[i - 1, j] / slope
        for _ in range(3):                                          # the interpolated altitude onto the level
            out[j] = _interpolated(dynamics, states[i - 1:i + 1, j], grid[i - 1:i + 1], f, body, epoch)
            f += (out[j, 3] - altitude_km) / slope
    return out


def event_values(dynamics: Dynamics, states: np.ndarray, t0: float, kind: str, body: str,
                 window: tuple[float, float], *, epoch: datetime | str | None = None) -> np.ndarray:
    """The event ``kind`` ("impact", "closest approach" or :func:`altitude_kind`) on ``body``
    ("Moon", "Earth") of each
    of ``states`` (N, 6) [LU, VU] at ``t0`` (TU): (N, 5) values :data:`EVENT_FIELDS` (time TU,
    latitude and longitude deg, altitude km, speed km/s); NaN rows where there is none. An impact
    is looked for from ``t0`` to ``window[1]``; an approach or a descent through an altitude within
    ``window`` (TU)."""
    x = np.atleast_2d(np.asarray(states, dtype=float))
    when = _epoch_of(dynamics, epoch)
    if kind == "impact":
        return _impact_values(dynamics, x, t0, window[1], body, when)
    if kind == "closest approach":
        return _approach_values(dynamics, x, t0, window, body, when)
    if kind.startswith("altitude ") and kind.endswith(" km"):
        return _crossing_values(dynamics, x, t0, window, body, float(kind.split()[1]), when)
    raise StateError(f"events: kind {kind!r} must be 'impact', 'closest approach' or altitude_kind(km)")


@dataclass(frozen=True)
class ParameterSpread:
    """The joint covariance of a state and the dynamics' solve-for parameters (such as the
    area-to-mass ratio): ``covariance`` (6 + P, 6 + P) [LU, VU, the parameters' units], ``names``
    (P,) and ``values`` (P,) of the parameters (the model the events are found with holds
    ``values``). The events' sigmas then carry the parameters' uncertainty too."""

    covariance: np.ndarray
    names: tuple
    values: np.ndarray


def _root(covariance: np.ndarray) -> np.ndarray:
    p = np.asarray(covariance, dtype=float)
    w, vecs = np.linalg.eigh(0.5 * (p + p.T))
    return vecs * np.sqrt(np.clip(w, 0.0, None))                    # columns s_i, root @ root.T == p


def _spread_values(dynamics, state, spread: ParameterSpread, t0, kind, body, window, epoch) -> np.ndarray:
    """The event's values (2 (6 + P), 5) at the states and parameters +- EPS_SIGMA along each
    column of the square root of the joint covariance (+ rows first): one model per point."""
    root = _root(spread.covariance)
    out = []
    for sign in (1.0, -1.0):
        for col in (sign * EPS_SIGMA * root).T:
            dyn = dynamics.with_parameters(**{n: float(v + d) for n, v, d in zip(spread.names, spread.values, col[6:])})
            out.append(event_values(dyn, (state + col[:6])[None], t0, kind, body, window, epoch=epoch)[0])
    return np.array(out)


def _linear_sigma(dynamics, state, covariance, t0, kind, body, window, epoch) -> dict[str, float]:
    """1-sigma of the event's values by central differences along the covariance's square root
    (``covariance`` (6, 6), or a :class:`ParameterSpread` of the state and parameters)."""
    if isinstance(covariance, ParameterSpread):
        vals = _spread_values(dynamics, state, covariance, t0, kind, body, window, epoch)
    else:
        delta = EPS_SIGMA * _root(covariance).T
        vals = event_values(dynamics, np.vstack([state + delta, state - delta]), t0, kind, body, window, epoch=epoch)
    n = vals.shape[0] // 2
    diff = vals[:n] - vals[n:]
    diff[:, 2] = (diff[:, 2] + 180.0) % 360.0 - 180.0                # longitudes wrap
    g = diff / (2.0 * EPS_SIGMA)                                     # (6 directions, 5 values) per sigma
    sig = np.sqrt(np.sum(g * g, axis=0))
    sig[0] *= units.TU_S
    return dict(zip(("time_s", "latitude_deg", "longitude_deg", "altitude_km", "speed_kms"), map(float, sig)))


def first_impact(dynamics: Dynamics, state: np.ndarray, t0: float, t_end: float) -> tuple[float, str] | None:
    """(time TU, body name) of the first impact of ``state`` (6,) between ``t0`` and ``t_end``
    (TU, either direction), or None."""
    prop = dynamics.propagate(np.asarray(state, dtype=float).reshape(1, 6), t0, np.array([t_end]))
    if bool(np.asarray(prop.alive)[0]):
        return None
    return float(np.asarray(prop.impact_time)[0]), dynamics.bodies[int(np.asarray(prop.impact_body)[0])].name


def _coarse_track(dynamics: Dynamics, state: np.ndarray, t0: float, t_end: float,
                  step_tu: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The nominal orbit ``state`` (6,) from ``t0`` to ``t_end`` on a grid of ``step_tu``: (grid
    (K,) TU, states (K, 1, 6), impact time TU or inf), one propagation shared by every body."""
    n = max(3, int(np.ceil(abs(t_end - t0) / step_tu)) + 1)
    grid = np.linspace(t0, t_end, n)
    if callable(getattr(dynamics, "dense_trajectory", None)):
        return grid, *_dense_track(dynamics, state, t0, grid)
    prop = dynamics.propagate(state[None], t0, grid[1:])
    states = np.concatenate([state[None, None], np.asarray(prop.states, dtype=float)])
    return grid, states, float(np.asarray(prop.impact_time)[0])


def _dense_track(dynamics: Dynamics, state: np.ndarray, t0: float, grid: np.ndarray) -> tuple[np.ndarray, float]:
    """(states (K, 1, 6), impact time TU or inf) of ``state`` (6,) at ``t0`` on ``grid`` (K,) from one
    dense integration, evaluated at every grid time together (a model integrating in another
    frame converts all of them at once, not time by time); frozen at the impact point after one."""
    traj = dynamics.dense_trajectory(state, t0, float(grid[-1]))
    impact = float(traj.impact_time)
    flying = grid <= traj.t1 if traj.t1 >= t0 else grid >= traj.t1
    states = np.empty((grid.size, 1, 6))
    states[flying, 0] = traj.states(grid[flying])
    states[~flying, 0] = traj.states(np.array([traj.t1]))[0]
    states[0, 0] = state
    return states, impact


def _approach_windows(dynamics: Dynamics, track: tuple[np.ndarray, np.ndarray, float],
                      body: str) -> list[tuple[float, float]]:
    """Windows (TU) of +-2 coarse steps about each interior minimum of the nominal orbit's
    distance to ``body`` on the grid of ``track`` (:func:`_coarse_track`)."""
    grid, states, impact = track
    r, _ = _distances(dynamics, states, grid, body)
    d = np.linalg.norm(r[:, 0], axis=1)
    d[grid >= impact] = np.inf
    k = np.flatnonzero((d[1:-1] < d[:-2]) & (d[1:-1] <= d[2:])) + 1
    step = grid[1] - grid[0]
    return [(max(grid[0] + 1e-12, grid[i] - 2 * step), min(grid[-1], grid[i] + 2 * step)) for i in k]


def _event(dynamics, state, covariance, t0, kind, body, window, epoch) -> OrbitEvent | None:
    vals = event_values(dynamics, state[None], t0, kind, body, window, epoch=epoch)[0]
    if not np.isfinite(vals[0]):
        return None
    sigma = _linear_sigma(dynamics, state, covariance, t0, kind, body, window, epoch) if covariance is not None else {}
    utc = units.format_utc(units.tu_to_utc(epoch, vals[0])) if epoch is not None else ""
    coords = "" if not np.isfinite(vals[1]) else ("selenographic (mean-Earth, DE421)" if body.lower() == "moon"
                                                  else "geodetic (WGS84)")
    return OrbitEvent(kind, dynamics.bodies[_body_index(dynamics, body)].name, float(vals[0]), utc, float(vals[1]),
                      float(vals[2]), float(vals[3]), float(vals[4]), coords, sigma)


def orbit_events(dynamics: Dynamics, state: np.ndarray, covariance: np.ndarray | None, t0: float, t_end: float, *,
                 epoch: datetime | str | None = None, approaches: bool = True,
                 altitude: tuple[str, float] | None = None) -> list[OrbitEvent]:
    """The impact (at most one: it ends the orbit) and the closest approaches to every impact body
    of the orbit ``state`` (6,) [LU, VU] at ``t0`` (TU) up to ``t_end`` (TU, > t0), in time order,
    each with its 1-sigma from ``covariance`` (6, 6) [LU, VU] (None: no sigmas). ``epoch``: the
    UTC of t = 0 (default the dynamics' own ``epoch``) for the UTC times and geodetic coordinates;
    ``approaches``: look for closest approaches (on a grid of :data:`APPROACH_STEP_MINUTES`);
    ``altitude``: (body name, km above its impact sphere) adds the first descent through that
    altitude."""
    x = np.asarray(state, dtype=float).reshape(6)
    if not (np.isfinite(t0) and np.isfinite(t_end) and t_end > t0):
        raise StateError(f"events: need finite times with t_end > t0 (TU), got {t0!r} and {t_end!r}")
    when = _epoch_of(dynamics, epoch)
    hit = first_impact(dynamics, x, t0, t_end)
    end = t_end if hit is None else hit[0]
    events = []
    if hit is not None:
        events.append(_event(dynamics, x, covariance, t0, "impact", hit[1], (t0, t_end), when))
    step = APPROACH_STEP_MINUTES * 60.0 / units.TU_S
    track = _coarse_track(dynamics, x, t0, end, step) if approaches and dynamics.bodies else None
    for body in ([b.name for b in dynamics.bodies] if track is not None else []):
        for window in _approach_windows(dynamics, track, body):
            events.append(_event(dynamics, x, covariance, t0, "closest approach", body, window, when))
    if altitude is not None:
        events.append(_event(dynamics, x, covariance, t0, altitude_kind(altitude[1]), altitude[0], (t0, end), when))
    return sorted((e for e in events if e is not None), key=lambda e: e.t_tu)


def times_until_impact(dynamics: Dynamics, state: np.ndarray, t0: float,
                       times: np.ndarray) -> tuple[np.ndarray, tuple[float, str] | None]:
    """The ``times`` (K,) TU (increasing, after ``t0``) at which the orbit ``state`` (6,) at ``t0``
    still flies, ending with the impact (:data:`IMPACT_MARGIN_S` before it) when it hits a body
    before the last of them; and (impact time TU, body name) or None. Times at or before ``t0``
    are kept as they are."""
    tt = np.asarray(times, dtype=float).reshape(-1)
    if tt.size == 0 or tt[-1] <= t0:
        return tt, None
    hit = first_impact(dynamics, state, t0, float(tt[-1]))
    if hit is None:
        return tt, None
    end = hit[0] - units.seconds_to_tu(IMPACT_MARGIN_S)
    return np.append(tt[tt < end], end), hit


def fit_events(dynamics: Dynamics, result, *, days: float = FIT_EVENT_DAYS,
               epoch: datetime | str | None = None) -> list[OrbitEvent]:
    """:func:`orbit_events` of a least-squares fit (a :class:`cistrack.least_squares.FitResult`)
    over ``days`` after its epoch, the covariance scaled as it is exported (by the noise scale
    squared when that exceeds 1), with the solve-for parameters it estimated (the area-to-mass
    ratio) set in ``dynamics``. ``epoch``: the UTC of t = 0 (default the dynamics' own)."""
    from cistrack.least_squares.result import sigma_factor
    from cistrack.least_squares.solve_for_parameters import fitted_dynamics

    scale = sigma_factor(result.noise_scale) ** 2
    t0 = float(result.epoch)
    return orbit_events(fitted_dynamics(dynamics, result), result.state, _spread_of(result, scale), t0,
                        t0 + float(units.days_to_tu(days)), epoch=epoch)


def _spread_of(result, scale: float = 1.0):
    """The covariance the events of a fit ``result`` map: its state's (6, 6), or with solve-for
    parameters a :class:`ParameterSpread` of state and parameters; times ``scale``."""
    names = tuple(getattr(result, "parameter_names", ()))
    full = getattr(result, "full_covariance", None)
    if not names or full is None:
        return result.covariance * scale
    return ParameterSpread(np.asarray(full, dtype=float) * scale, names, np.asarray(result.parameters, dtype=float))


def prediction_end(dynamics: Dynamics, result, times: np.ndarray, *, epoch: datetime | str | None = None,
                   altitude: tuple[str, float] | None = None) -> tuple[np.ndarray, OrbitEvent | None]:
    """:func:`times_until_impact` for a fit ``result`` (its state, covariance and epoch) over
    ``times`` (K,) TU, and the impact as an :class:`OrbitEvent` with its 1-sigma (None when the
    orbit flies through): what an export writes up to, and says where it ends. With ``altitude``
    (body name, km above its impact sphere) the orbit ends where it first descends through that
    altitude instead (the last time is that of the crossing)."""
    t0, x, when = float(result.epoch), np.asarray(result.state, dtype=float), _epoch_of(dynamics, epoch)
    kept, hit = times_until_impact(dynamics, x, t0, times)
    window = (t0, float(np.max(times)) if hit is None else hit[0])
    if altitude is not None and window[1] > t0:
        event = _event(dynamics, x, _spread_of(result), t0, altitude_kind(altitude[1]), altitude[0], window, when)
        if event is not None:
            return np.append(kept[kept < event.t_tu], event.t_tu), event
    if hit is None:
        return kept, None
    return kept, _event(dynamics, x, _spread_of(result), t0, "impact", hit[1], (t0, float(np.max(times))), when)


def event_lines(events: list[OrbitEvent], days: float = FIT_EVENT_DAYS) -> list[str]:
    """The lines a fit summary prints for ``events`` found over ``days`` after the fit epoch
    (indented two spaces, each under 120 columns)."""
    if not events:
        return [f"  no impact and no closest approach within {days:g} days of the fit epoch"]
    head = f"  impacts and closest approaches within {days:g} days of the fit epoch (1-sigma by linear mapping):"
    lines = ["  " + line for e in events for line in e.lines() if line != UNDETERMINED_NOTE]
    return [head] + lines + (["  " + UNDETERMINED_NOTE] if any(e.undetermined() for e in events) else [])
