"""Burn plans of a truth trajectory: maneuver plans ``impulse``, ``burns`` and ``station-keeping``.

A scenario's ``[truth.maneuvers]`` table names one (docs/maneuvers.md)::

    [truth.maneuvers]
    name = "impulse"
    t_days = 3.5                 # days since the scenario epoch
    delta_v_ms = 1.0             # m/s
    direction = "in-track"       # or anti-in-track, radial, anti-radial, cross-track, anti-cross-track
    frame = "rtn-moon"           # or rtn-earth, vnb, synodic (see local_frames)

Each plan turns its burns into :class:`~cistrack.interfaces.maneuvers.Impulse` objects (synodic
VU) along the truth: a burn given in a local frame is resolved at its time on the trajectory
flown with the earlier burns, at the pre-burn state, in one sweep (each burn's state flown by the
base model from the state just after the burn before it). Burns outside the run's span
``(t0, t_end]`` are not flown.
"""
from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np

from cistrack import units
from cistrack.api import hookimpl
from cistrack.errors import ConfigError, ParameterError, invisible_character, quoted
from cistrack.interfaces.component import check_choice, check_int, check_nonnegative, check_range
from cistrack.interfaces.maneuvers import Impulse, ManeuverPlan
from cistrack.propagation.impulses import MS_PER_VU

from .local_frames import DIRECTIONS, FRAMES, body_position, direction_vector, frame_axes

__all__ = ["ImpulsePlan", "BurnsPlan", "StationKeepingPlan", "BurnSpec", "resolve_burns"]

_BURN_KEYS = ("t_days", "delta_v_ms", "direction", "frame", "vector_ms", "label")

MAX_LABEL_CHARACTERS = 100
"""Longest burn label: a name for reports, printed on the run's log lines."""
MAX_DELTA_V_MS = 10_000.0
"""The largest burn a plan takes, m/s: more than any cislunar transfer needs (a larger one is a unit
mistake, km/s or cm/s for m/s)."""


class BurnSpec:
    """One burn as a plan describes it: time (TU), components (3,) m/s in ``frame``, a label."""

    def __init__(self, t: float, vector_ms: np.ndarray, frame: str, label: str) -> None:
        self.t, self.vector_ms, self.frame, self.label = float(t), np.asarray(vector_ms, dtype=float), frame, label


def _flown_to(dynamics, x: np.ndarray, t: float, t_burn: float) -> np.ndarray:
    """The state (6,) at ``t_burn`` of ``x`` (6,) flown by ``dynamics`` from ``t``; ConfigError when
    it hits a body on the way."""
    prop = dynamics.propagate(x[None], t, t_burn)
    if not prop.alive[0]:
        raise ConfigError(f"the truth hits a body at t = {units.tu_to_days(prop.impact_time[0]):.3f} days, "
                          f"before the burn at {units.tu_to_days(t_burn):.3f} days")
    return np.array(prop.final[0], dtype=float)


def resolve_burns(dynamics, x0: np.ndarray, t0: float, t_end: float, burns: list[BurnSpec]) -> list[Impulse]:
    """The impulses (synodic VU, sorted by time) of ``burns`` inside ``(t0, t_end]``, each resolved
    in its frame at the pre-burn state of the truth flown with the earlier ones (burns at one time
    all at the state before the first of them). One sweep, each burn's state flown from the one
    before it: 10,000 burns had each been flown from ``t0`` through all the earlier ones, which
    took minutes (probe J3); a plan of many burns says how far it has got."""
    inside = sorted((b for b in burns if t0 < b.t <= t_end), key=lambda b: b.t)
    return _sweep(dynamics, np.asarray(x0, dtype=float), float(t0), inside)[0]


def _sweep(dynamics, x0: np.ndarray, t0: float, burns: list[BurnSpec]) -> tuple[list[Impulse], np.ndarray, float]:
    """(impulses, state just after the last, its time) of ``burns`` (in time order, after ``t0``)
    resolved along ``x0`` (6,) flown from ``t0``, each from the state after the one before."""
    out: list[Impulse] = []
    x, t, x_b = x0.copy(), t0, None
    progress = _Progress(len(burns))
    for b in burns:
        if x_b is None or b.t != t:
            x_b = _flown_to(dynamics, x, t, b.t)
            x, t = x_b.copy(), b.t
        dv = frame_axes(b.frame, x_b, b.t, dynamics) @ b.vector_ms / MS_PER_VU
        x[3:] += dv
        out.append(Impulse(b.t, dv, b.label))
        progress.step(len(out))
    return out, x, t


class _Progress:
    """A line on the ``cistrack`` logger every 10 s while a long plan of burns is resolved."""

    every_s = 10.0

    def __init__(self, total: int) -> None:
        self.total, self.next = total, time.monotonic() + self.every_s

    def step(self, done: int) -> None:
        if done < self.total and time.monotonic() >= self.next:
            logging.getLogger("cistrack").info(f"resolving the truth's burns: {done:,} of {self.total:,} ...")
            self.next = time.monotonic() + self.every_s


def _check_vector(owner, value: Any) -> list[float]:
    """``vector_ms``: None or an empty list (unset), or 3 finite numbers."""
    if value is None:
        return []
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) not in (0, 3) or not all(
            isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool) and np.isfinite(v)
            for v in value):
        owner._fail("vector_ms", value, "must be 3 finite numbers (m/s, the burn's components in its frame) "
                                        "or an empty list (use delta_v_ms and direction)")
    if value and math.hypot(*(float(v) for v in value)) > MAX_DELTA_V_MS:  # no overflow: numpy's norm of
        # [1e308, 1e308, 0] had printed "overflow encountered in dot" before this refusal (probe I8)
        owner._fail("vector_ms", value, f"the burn's size must be at most {MAX_DELTA_V_MS:g} m/s")
    return [float(v) for v in value]


EARLIEST_BURN_DAYS = 1.0 / 86400.0
"""The earliest burn a plan takes, days after the scenario epoch (1 second): a burn at the epoch is
the initial state's velocity, and one 1e-300 days after it, accepted where 0 was refused, had been
listed in the manifest "at t_days 0.0" (probe J9)."""


def _check_t_days(owner, value: Any) -> float:
    v = check_range(owner, "t_days", value, -math.inf, math.inf)  # a finite number
    if v < EARLIEST_BURN_DAYS:
        owner._fail("t_days", value, f"must be at least 1 second ({EARLIEST_BURN_DAYS:.5g} days) after the scenario "
                                     "epoch (a burn at the epoch is the initial state's velocity: give it in [truth])")
    return v


def _check_delta_v(owner, value: Any) -> float:
    return check_range(owner, "delta_v_ms", value, 0.0, MAX_DELTA_V_MS)


DEFAULT_DELTA_V_MS = 1.0
"""A burn's size when neither delta_v_ms nor vector_ms is given, m/s."""
DEFAULT_DIRECTION = "in-track"
"""A burn's direction when neither direction nor vector_ms is given."""


def _check_one_burn_form(owner, vector_ms: list[float], delta_v_ms: Any, direction: Any) -> None:
    """vector_ms replaces delta_v_ms and direction: giving both forms is refused, whatever their
    values (a default value written out included), since one would be dropped."""
    given = [f"{k} = {quoted(v)}" for k, v in (("delta_v_ms", delta_v_ms), ("direction", direction)) if v is not None]
    if vector_ms and given:
        owner._fail("vector_ms", vector_ms, f"gives the burn's components, and {' with '.join(given)} "
                                            f"give{'s' if len(given) == 1 else ''} it too; give one form (vector_ms, "
                                            "or delta_v_ms and direction). A --set cannot remove a key the scenario "
                                            "file writes (example-1-burn writes delta_v_ms and direction): give "
                                            "vector_ms in a copy of the file without them, or set a plan of another "
                                            "name, which replaces the whole table: --set 'truth.maneuvers={name="
                                            "\"burns\", burns=[{t_days=T, vector_ms=[X, Y, Z]}]}'")


def _outside(specs: list[BurnSpec], t0: float, t_end: float) -> list[str]:
    """The burns of ``specs`` outside ``(t0, t_end]`` TU, each as 'LABEL at D days'."""
    return [f"{b.label} at {float(units.tu_to_days(b.t)):.12g} days" for b in specs if not t0 < b.t <= t_end]


def _check_burn_frame(owner, frame: Any, vector_ms: list[float], direction: Any) -> None:
    check_choice(owner, "frame", frame, FRAMES)
    if direction is not None:
        check_choice(owner, "direction", direction, DIRECTIONS)
    if frame == "synodic" and not vector_ms:
        owner._fail("frame", frame, "a burn in the synodic frame is given by vector_ms (x, y, z in m/s); "
                                    "or use a local frame: " + ", ".join(f for f in FRAMES if f != "synodic"))


def _describe(vector_ms: list[float], delta_v_ms: float, direction: str, frame: str) -> str:
    if vector_ms:  # + 0.0: a zero given as -0.0 is said "0", not "-0"
        return f"[{', '.join(f'{v + 0.0:g}' for v in vector_ms)}] m/s ({frame})"
    return f"{delta_v_ms + 0.0:g} m/s {direction} ({frame})"


class ImpulsePlan(ManeuverPlan):
    """One impulsive burn at a given time, along a direction of a local frame of the truth.

    Parameters
    ----------
    t_days : float
        Time of the burn, days since the scenario epoch: at least 1 second (1.1574e-05 days) after it
        (a burn after the run's end is not flown).
    delta_v_ms : float
        Size of the burn, m/s (0 to 10,000); unset (None), 1 m/s unless vector_ms gives the burn.
    direction : str
        Direction of the burn in its frame: one of in-track, anti-in-track, radial, anti-radial,
        cross-track, anti-cross-track; unset (None), in-track unless vector_ms gives the burn.
    frame : str
        The local frame: rtn-moon (radial, in-track, cross-track about the Moon, in the synodic
        frame), rtn-earth (the same about the Earth), vnb (velocity, normal, binormal of the
        synodic velocity) or synodic (needs vector_ms).
    vector_ms : list of float
        The burn as 3 components in m/s along the frame's axes (R, T, N; V, N, B; or x, y, z),
        instead of delta_v_ms and direction (giving it with either of them is refused, whatever
        their values); empty (the default) to use them.
    label : str
        A name for reports (default: burn): at most 100 printable characters.
    """

    def __init__(self, t_days: float = 1.0, delta_v_ms: float | None = None, direction: str | None = None,
                 frame: str = "rtn-moon", vector_ms: list[float] | None = None, label: str = "") -> None:
        self.t_days = _check_t_days(self, t_days)
        size = None if delta_v_ms is None else _check_delta_v(self, delta_v_ms)
        self.vector_ms = _check_vector(self, vector_ms)
        _check_burn_frame(self, frame, self.vector_ms, direction)
        _check_one_burn_form(self, self.vector_ms, delta_v_ms, direction)
        vector_form = bool(self.vector_ms)  # the form not given stays None (get_params rebuilds the plan)
        self.delta_v_ms = None if vector_form else (DEFAULT_DELTA_V_MS if size is None else size)
        self.direction = None if vector_form else (DEFAULT_DIRECTION if direction is None else direction)
        self.frame = frame
        if not isinstance(label, str) or len(label) > MAX_LABEL_CHARACTERS or invisible_character(label):
            self._fail("label", label, f"must be a string of at most {MAX_LABEL_CHARACTERS} printable characters (no "
                                       "line breaks, tabs or invisible formatting characters such as bidirectional "
                                       "overrides)")
        self.label = label

    def burn(self, default_label: str = "burn") -> BurnSpec:
        """This burn as a :class:`BurnSpec` (time TU, components m/s in its frame)."""
        vec = (np.array(self.vector_ms) if self.vector_ms
               else direction_vector(self.frame, self.direction, self.delta_v_ms))
        what = _describe(self.vector_ms, self.delta_v_ms, self.direction, self.frame)
        return BurnSpec(float(units.days_to_tu(self.t_days)), vec, self.frame, f"{self.label or default_label}: {what}")

    def impulses(self, dynamics, x0: np.ndarray, t0: float, t_end: float) -> list[Impulse]:
        return resolve_burns(dynamics, x0, t0, t_end, [self.burn()])

    def burns_outside(self, t0: float, t_end: float) -> list[str]:
        return _outside([self.burn()], t0, t_end)


class BurnsPlan(ManeuverPlan):
    """A list of impulsive burns, each given as the impulse plan's one burn.

    Parameters
    ----------
    burns : list of tables
        One table per burn with the keys t_days (required), delta_v_ms, direction, frame,
        vector_ms and label, as for the impulse plan (the same defaults). Empty: no burn.
    """

    def __init__(self, burns: list[dict[str, Any]] | None = None) -> None:
        self.burns = [] if burns is None else burns
        if not isinstance(self.burns, (list, tuple)):
            self._fail("burns", burns, "must be a list of tables (t_days, delta_v_ms, direction, frame, vector_ms, label)")
        self._plans = [self._one(i, table) for i, table in enumerate(self.burns)]

    def _one(self, i: int, table: Any) -> ImpulsePlan:
        where = f"burns[{i}]"
        if not isinstance(table, dict):
            self._fail(where, table, "must be a table with t_days and the impulse plan's keys")
        unknown = sorted(set(table) - set(_BURN_KEYS))
        if unknown or "t_days" not in table:
            self._fail(where, table, (f"unknown key(s) {', '.join(unknown)}; " if unknown else "missing key t_days; ")
                       + f"allowed keys: {', '.join(_BURN_KEYS)}")
        try:
            return ImpulsePlan(**table)
        except ParameterError as exc:
            raise ParameterError(f"{self._label()}: parameter '{where}': {str(exc).split(': ', 1)[-1]}") from None

    def _specs(self) -> list[BurnSpec]:
        """The burns in time order, unlabelled ones named "burn N" in that order (as the log numbers them)."""
        in_time = sorted(self._plans, key=lambda p: p.t_days)
        return [p.burn(f"burn {i + 1}") for i, p in enumerate(in_time)]

    def impulses(self, dynamics, x0: np.ndarray, t0: float, t_end: float) -> list[Impulse]:
        return resolve_burns(dynamics, x0, t0, t_end, self._specs())

    def burns_outside(self, t0: float, t_end: float) -> list[str]:
        return _outside(self._specs(), t0, t_end)


class StationKeepingPlan(ManeuverPlan):
    """Small burns at successive apolune passages (once per revolution), as station-keeping makes.

    Each burn is at a local maximum of the distance to the Moon along the truth flown with the
    earlier burns, the first after first_after_days; those that fall inside the run are flown.

    Parameters
    ----------
    delta_v_ms : float
        Size of each burn, m/s (0 to 10,000).
    first_after_days : float
        The first burn is at the first apolune after this time, days since the scenario epoch (>= 0).
    n_burns : int
        Number of burns, one per apolune passage (>= 1).
    direction : str
        Direction of each burn in its frame: one of in-track, anti-in-track, radial, anti-radial,
        cross-track, anti-cross-track.
    frame : str
        The local frame: rtn-moon (radial, in-track, cross-track about the Moon, in the synodic
        frame), rtn-earth (the same about the Earth) or vnb (velocity, normal, binormal of the
        synodic velocity).
    """

    search_step_tu = 0.005
    """Grid on which the distance to the Moon is scanned for its maxima, TU (31 minutes)."""

    def __init__(self, delta_v_ms: float = 0.1, first_after_days: float = 0.0, n_burns: int = 2,
                 direction: str = "in-track", frame: str = "rtn-moon") -> None:
        self.delta_v_ms = _check_delta_v(self, delta_v_ms)
        self.first_after_days = check_nonnegative(self, "first_after_days", first_after_days)
        self.n_burns = check_int(self, "n_burns", n_burns, minimum=1, maximum=10_000)
        check_choice(self, "frame", frame, [f for f in FRAMES if f != "synodic"])
        check_choice(self, "direction", direction, DIRECTIONS)
        self.direction, self.frame = direction, frame

    def impulses(self, dynamics, x0: np.ndarray, t0: float, t_end: float) -> list[Impulse]:
        vec = direction_vector(self.frame, self.direction, self.delta_v_ms)
        what = _describe([], self.delta_v_ms, self.direction, self.frame)
        out: list[Impulse] = []
        x, t = np.asarray(x0, dtype=float), float(t0)  # the truth just after the last burn (one sweep: probe J3)
        t_from = max(t0, t0 + float(units.days_to_tu(self.first_after_days)))
        for k in range(self.n_burns):
            t_b = next_apolune(dynamics, x, t, t_from, t_end, self.search_step_tu)
            if t_b is None:
                break
            burn, x, t = _sweep(dynamics, x, t, [BurnSpec(t_b, vec, self.frame, f"station-keeping {k + 1}: {what}")])
            out += burn
            t_from = t_b + self.search_step_tu
        self._found = (len(out), float(t0), float(t_end))
        return out

    def burns_outside(self, t0: float, t_end: float) -> list[str]:
        """The burns of ``n_burns`` whose apolune the run does not reach (known once
        :meth:`impulses` has searched this span)."""
        found, a, b = getattr(self, "_found", (None, None, None))
        if found is None or (a, b) != (float(t0), float(t_end)) or found >= self.n_burns:
            return []
        first = found + 1
        which = f"station-keeping burn {first}" if first == self.n_burns else \
            f"station-keeping burns {first} to {self.n_burns}"
        why = (f"no apolune passage between first_after_days = {self.first_after_days:g} and the end of the run"
               if found == 0 else f"the run ends before apolune passage {first}")
        return [f"{which} ({why})"]


def _evaluator(dynamics, x0: np.ndarray, t0: float, t_end: float):
    """``states(ts) -> (K, 6)`` along the trajectory from ``x0`` at ``t0``: one dense integration
    over ``[t0, t_end]`` when the model has it, else a propagation per call."""
    x0 = np.asarray(x0, dtype=float)
    dense = getattr(dynamics, "dense_trajectory", None)
    if callable(dense):
        traj = dense(x0, t0, t_end)
        if not traj.alive:
            raise ConfigError(f"the truth hits a body at t = {units.tu_to_days(traj.impact_time):.3f} days")
        return traj.states

    def states(ts):
        ts = np.atleast_1d(np.asarray(ts, dtype=float))
        return dynamics.propagate(x0[None], t0, ts).states[:, 0]

    return states


def next_apolune(dynamics, x0: np.ndarray, t0: float, t_from: float, t_end: float, step: float) -> float | None:
    """The first local maximum (TU) of the distance to the Moon in ``(t_from, t_end)`` along the
    trajectory of ``x0`` (6,) from ``t0`` under ``dynamics``, or None: scanned on a grid of
    ``step`` TU and refined to 1e-10 TU."""
    from scipy.optimize import minimize_scalar

    if t_end - t_from < 2 * step:
        return None
    states = _evaluator(dynamics, x0, t0, t_end)
    grid = np.append(np.arange(t_from, t_end, step), t_end)

    def dist(ts):
        ts = np.atleast_1d(ts)
        moon = np.stack([body_position(dynamics, "Moon", float(t)) for t in ts])
        return np.linalg.norm(states(ts)[:, :3] - moon, axis=1)

    d = dist(grid)
    peaks = np.flatnonzero((d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:])) + 1
    if peaks.size == 0:
        return None
    i = int(peaks[0])
    res = minimize_scalar(lambda t: -dist(t)[0], bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                          options={"xatol": 1e-10})
    return float(res.x)


@hookimpl
def cistrack_register(registry):
    registry.add("maneuver-plan", "impulse", ImpulsePlan)
    registry.add("maneuver-plan", "burns", BurnsPlan)
    registry.add("maneuver-plan", "station-keeping", StationKeepingPlan)
