"""The trajectory of an observer in space, propagated once by the run's dynamics.

The observer passes through the state ``x0`` at ``t0`` (TU since the scenario epoch, t0 <= 0);
its state at any later time comes from the dynamics' dense output at tight tolerance
(``rtol`` 1e-13), so its own integration error (~1e-12 LU) stays far below what any angle
measurement resolves. The span grows in fixed chunks of ``CHUNK_DAYS``: the state at a time t is
always taken from the span ``[t0, t0 + k CHUNK]`` with the smallest k covering t, so it does not
depend on which times were asked for before (same numbers in any process and cache state).

A dynamics model without ``dense_trajectory`` (a third-party :class:`Dynamics`) is propagated
from ``x0`` to the times asked for, in one ``propagate`` call per request.
"""
from __future__ import annotations

import math
from datetime import timedelta

import numpy as np

from cistrack import units
from cistrack.units import TU_S, parse_utc, state_from_km
from cistrack.errors import ConfigError, MeasurementError

__all__ = ["ObserverOrbit", "start_of_orbit", "observer_start", "CHUNK_DAYS", "OBSERVER_RTOL", "OBSERVER_ATOL",
           "DEFAULT_ORBIT", "MAX_STATE_AGE_DAYS"]

CHUNK_DAYS: float = 32.0
"""Length of each extension of the observer's propagated span, days."""
OBSERVER_RTOL: float = 1e-13
OBSERVER_ATOL: float = 1e-15
DEFAULT_ORBIT: str = "dro-2-1"
"""Catalog orbit an observer flies when given neither ``orbit`` nor ``state_km``."""
MAX_STATE_AGE_DAYS: float = 366.0
"""Largest time from ``state_epoch`` to the scenario epoch, days: the observer is propagated over it."""


class ObserverOrbit:
    """Observer states under ``dynamics`` from ``x0`` (6,) synodic at ``t0`` (TU, <= 0).

    ``label`` names the sensor in errors.
    """

    def __init__(self, dynamics, x0: np.ndarray, t0: float, label: str = "space-telescope") -> None:
        self.dynamics = dynamics
        self.x0 = np.array(x0, dtype=float).reshape(6)
        self.t0 = float(t0)
        self.label = label
        self._spans: dict[int, object] = {}

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_spans"] = {}
        return state

    def _chunk(self) -> float:
        return float(units.days_to_tu(CHUNK_DAYS))

    def _span(self, k: int):
        dense = self._spans.get(k)
        if dense is None:
            t1 = self.t0 + k * self._chunk()
            dense = self.dynamics.dense_trajectory(self.x0, self.t0, t1, rtol=OBSERVER_RTOL, atol=OBSERVER_ATOL)
            if not dense.alive:
                bodies = self.dynamics.bodies
                b = int(dense.impact_body)
                name = bodies[b].name if 0 <= b < len(bodies) else "a body"
                raise ConfigError(f"sensor {self.label!r}: the observer's orbit hits {name} at t = "
                                  f"{units.tu_to_days(dense.impact_time):.3f} days; choose another orbit or state")
            self._spans[k] = dense
        return dense

    def states(self, t) -> np.ndarray:
        """Observer states (K, 6) synodic at t (scalar or (K,) TU, each >= t0)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1)
        if not np.all(np.isfinite(tt)):
            raise MeasurementError(f"sensor {self.label!r}: times contain NaN or infinity")
        if tt.size and tt.min() < self.t0 - 1e-12:
            raise MeasurementError(f"sensor {self.label!r}: the observer's orbit starts at t = "
                                   f"{units.tu_to_days(self.t0):.4f} d; asked for t = {units.tu_to_days(tt.min()):.4f} d")
        if not callable(getattr(self.dynamics, "dense_trajectory", None)):
            return self._propagated(tt)
        ks = np.maximum(1, np.ceil((tt - self.t0) / self._chunk() - 1e-12)).astype(int)
        out = np.empty((tt.size, 6))
        for k in np.unique(ks):
            rows = ks == k
            out[rows] = self._span(int(k)).states(tt[rows])
        return out

    def _propagated(self, tt: np.ndarray) -> np.ndarray:
        uniq, inv = np.unique(tt, return_inverse=True)
        out = np.empty((uniq.size, 6))
        at_start = uniq <= self.t0
        out[at_start] = self.x0
        if (~at_start).any():
            prop = self.dynamics.propagate(self.x0[None], self.t0, uniq[~at_start])
            out[~at_start] = prop.states[:, 0, :]
        return out[inv]


def start_of_orbit(registry_orbit, phase: float) -> tuple[np.ndarray, float]:
    """(x0, t0) for an observer ``phase`` (fraction of a period, in [0, 1)) along a catalog orbit:
    it passes the catalog state at t0 = -phase x period, so at t = 0 it is ``phase`` of the way
    round. An orbit without a period (not periodic) needs phase 0."""
    period = registry_orbit.period
    if period is None or not math.isfinite(period):
        if phase != 0.0:
            raise ConfigError(f"orbit {registry_orbit.name!r} is not periodic: its phase must be 0")
        return np.asarray(registry_orbit.state, dtype=float).copy(), 0.0
    return np.asarray(registry_orbit.state, dtype=float).copy(), -float(phase) * float(period)


def _state_t0(state_epoch, epoch, fail) -> float:
    """TU from the scenario ``epoch`` (datetime) to ``state_epoch`` (UTC text, "" = the epoch):
    at most 0, at least -:data:`MAX_STATE_AGE_DAYS` days."""
    if not state_epoch:
        return 0.0
    try:
        when = parse_utc(state_epoch)
    except (ValueError, TypeError, OverflowError):
        fail("state_epoch", state_epoch, "must be an ISO-8601 UTC time")
    days = units.elapsed_seconds(epoch, when) / 86400.0  # elapsed: leap seconds counted
    if not -MAX_STATE_AGE_DAYS <= days <= 0.0:
        earliest = units.format_utc(epoch - timedelta(days=MAX_STATE_AGE_DAYS))[:19] + "Z"
        fail("state_epoch", state_epoch, f"must lie from {earliest} to the scenario epoch "
                                         f"{units.format_utc(epoch)[:19]}Z (at most {MAX_STATE_AGE_DAYS:g} days "
                                         f"before it; it is {-days:.6g} days before)")
    return days * 86400.0 / TU_S


def observer_start(orbit: str | None, phase: float, state_km, state_epoch: str, epoch, fail):
    """(x0, t0, orbit) of an observer given by a catalog ``orbit`` (None: :data:`DEFAULT_ORBIT`)
    and ``phase``, or by ``state_km`` (synodic km, km/s) at ``state_epoch`` (UTC text, "" =
    ``epoch``, a datetime; at most :data:`MAX_STATE_AGE_DAYS` before it); ``orbit`` and
    ``state_km`` are exclusive. ``fail(name, value, allowed)`` reports a bad parameter. The
    orbit returned is "" for a state."""
    if state_km is not None:
        s = state_km
        if (not isinstance(s, (list, tuple)) or len(s) != 6
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in s)
                or not np.all(np.isfinite(np.asarray(s, dtype=float)))):
            fail("state_km", s, "must be 6 finite numbers [x, y, z km, vx, vy, vz km/s]")
        if orbit not in (None, ""):
            fail("orbit", orbit, "cannot go with 'state_km' (also given): 'orbit' and 'state_km' are "
                                 "exclusive; give 'orbit' (with 'phase') or 'state_km' (with 'state_epoch'), "
                                 "not both")
        t0 = _state_t0(state_epoch, epoch, fail)
        return state_from_km(np.asarray(s, dtype=float)), t0, ""
    if state_epoch:
        fail("state_epoch", state_epoch, "goes with 'state_km' (a catalog orbit uses 'phase')")
    orbit = DEFAULT_ORBIT if orbit is None else orbit
    from cistrack.api import default_registry
    reg = default_registry()
    names = reg.names("orbit")
    if orbit not in names:
        fail("orbit", orbit, "must be a registered orbit, one of: " + ", ".join(names))
    try:
        x0, t0 = start_of_orbit(reg.get("orbit", orbit).factory, phase)
    except ConfigError as exc:
        fail("phase", phase, str(exc))
    return x0, t0, orbit
