"""Tasking schedules: when the sensor is asked to observe (registered kind ``"schedule"``).

One general policy, :class:`PhasedSchedule` (``"phased"``), is a list of phases; each phase is a
time window and/or a range of pass numbers with a cadence rule. Everything else is a preset that
builds phases:

=====================  ======================================================================
name                   policy
=====================  ======================================================================
``every``              every ``interval_minutes`` while visible (optionally random spacing)
``random-consecutive`` ``count`` consecutive measurements at a random place in every pass
``phased``             any list of phases (tables of plain numbers and strings)
``paper-example-1``    first pass every 40–60 min (random spacing); then 5 random consecutive
                       measurements per pass, spaced the same way
``paper-example-2``    every 40 min while visible for 33 h; 10-day shutoff; every 16 h
                       (clock) when visible
``paper-example-3``    every 40 min while visible for 24 h; 150-day shutoff; every 40 min
                       while visible
=====================  ======================================================================

A phase is a table with these keys (all optional but ``rule``):

``rule``
    ``"every"``, ``"random-consecutive"`` or ``"off"`` (an explicit shutoff: no measurements).
``start_hours`` / ``start_days``, ``end_hours`` / ``end_days``
    The window, relative to the schedule's origin (default 0 and infinity). Use one unit per end.
``from_pass``, ``to_pass``
    Pass numbers the phase applies to, 0-based, ``to_pass`` exclusive (default all passes).
    Pass 0 is the first pass handed to :meth:`plan`.
``interval_minutes``, ``interval_max_minutes``
    Spacing between measurements; with ``interval_max_minutes`` > ``interval_minutes`` each
    spacing is drawn uniformly from [interval_minutes, interval_max_minutes].
``align`` (rule ``every``)
    ``"pass"`` (default): the cadence restarts at the start of each pass (inside the window);
    ``"clock"``: one grid from the window start, keeping the grid times at which the target is
    visible ("every 16 h when visible").
``count`` (rule ``random-consecutive``)
    Measurements per pass (default 5). A pass too short for all of them gets as many as fit,
    starting at its beginning.

The origin is the start of the first pass (``origin = "first-pass"``, default) or the epoch
(``origin = "epoch"``; then ``start_days = 30`` means "a fixed cadence after 30 days from the
epoch"). Measurements of all phases are merged; times are strictly increasing, inside a pass
and not after ``t_end``.
"""
from __future__ import annotations

import copy
import math
from typing import Any, Sequence

import numpy as np

from cistrack.component import check_choice, check_int, check_nonnegative, check_positive
from cistrack.hookspecs import hookimpl
from cistrack.interfaces import Pass, Schedule
from cistrack.units import TU_S

__all__ = ["PhasedSchedule", "EverySchedule", "RandomConsecutiveSchedule",
           "PaperExample1Schedule", "PaperExample2Schedule", "PaperExample3Schedule", "RULES"]

RULES = ("every", "random-consecutive", "off")
_HOUR_TU = 3600.0 / TU_S
_MIN_TU = 60.0 / TU_S
_DAY_TU = 86400.0 / TU_S
_ALLOWED_KEYS = {"rule", "start_hours", "start_days", "end_hours", "end_days", "from_pass",
                 "to_pass", "interval_minutes", "interval_max_minutes", "align", "count"}
_EPS = 1e-12


class _Phase:
    """A validated phase in TU (internal)."""

    def __init__(self, rule, start, end, from_pass, to_pass, dt_min, dt_max, align, count):
        self.rule, self.start, self.end = rule, start, end
        self.from_pass, self.to_pass = from_pass, to_pass
        self.dt_min, self.dt_max, self.align, self.count = dt_min, dt_max, align, count

    def spacings(self, n: int, rng: np.random.Generator) -> np.ndarray:
        if self.dt_max > self.dt_min:
            return rng.uniform(self.dt_min, self.dt_max, n)
        return np.full(n, self.dt_min)


class PhasedSchedule(Schedule):
    """General tasking policy: a list of phases, each a window with a cadence rule.

    Parameters
    ----------
    phases : list of tables
        See the module documentation for the keys. Default: every 40 minutes while visible.
    origin : str
        ``"first-pass"`` (phase windows count from the start of the first pass) or ``"epoch"``.
    """

    def __init__(self, phases: list[dict[str, Any]] | None = None, origin: str = "first-pass") -> None:
        if phases is None:
            phases = [{"rule": "every", "interval_minutes": 40.0}]
        self.phases = copy.deepcopy(phases)
        self.origin = check_choice(self, "origin", origin, ("first-pass", "epoch"))
        self._phases = self._parse(self.phases, "phases")

    # -- validation -----------------------------------------------------------------------------
    def _parse(self, phases: Any, pname: str) -> list[_Phase]:
        if not isinstance(phases, (list, tuple)) or not phases:
            self._fail(pname, phases, "must be a non-empty list of tables (one per phase)")
        return [self._parse_one(p, f"{pname}[{i}]") for i, p in enumerate(phases)]

    def _parse_one(self, p: Any, where: str) -> _Phase:
        if not isinstance(p, dict):
            self._fail(where, p, "must be a table with at least 'rule'")
        unknown = sorted(set(p) - _ALLOWED_KEYS)
        if unknown:
            self._fail(where, p, f"unknown key(s) {unknown}; allowed: {sorted(_ALLOWED_KEYS)}")
        rule = check_choice(self, f"{where}.rule", p.get("rule"), RULES)
        start = self._time(p, where, "start", 0.0)
        end = self._time(p, where, "end", math.inf)
        if end <= start:
            self._fail(where, p, "the phase must end after it starts")
        from_pass = check_int(self, f"{where}.from_pass", p.get("from_pass", 0), minimum=0)
        to_pass = p.get("to_pass", None)
        if to_pass is not None:
            to_pass = check_int(self, f"{where}.to_pass", to_pass, minimum=from_pass + 1)
        dt_min = dt_max = 0.0
        if rule != "off":
            if "interval_minutes" not in p:
                self._fail(where, p, f"rule '{rule}' needs 'interval_minutes'")
            dt_min = check_positive(self, f"{where}.interval_minutes", p["interval_minutes"]) * _MIN_TU
            dt_max = dt_min
            if "interval_max_minutes" in p:
                hi = check_positive(self, f"{where}.interval_max_minutes", p["interval_max_minutes"])
                if hi * _MIN_TU < dt_min:
                    self._fail(f"{where}.interval_max_minutes", hi, "must be >= interval_minutes")
                dt_max = hi * _MIN_TU
        align = check_choice(self, f"{where}.align", p.get("align", "pass"), ("pass", "clock"))
        count = check_int(self, f"{where}.count", p.get("count", 5), minimum=1)
        return _Phase(rule, start, end, from_pass, to_pass, dt_min, dt_max, align, count)

    def _time(self, p: dict, where: str, which: str, default: float) -> float:
        h, d = p.get(f"{which}_hours"), p.get(f"{which}_days")
        if h is not None and d is not None:
            self._fail(where, p, f"give '{which}_hours' or '{which}_days', not both")
        if h is None and d is None:
            return default
        key, value, unit = (f"{which}_hours", h, _HOUR_TU) if h is not None else (f"{which}_days", d, _DAY_TU)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value == math.inf:
            return math.inf
        return check_nonnegative(self, f"{where}.{key}", value) * unit

    # -- planning -------------------------------------------------------------------------------
    def plan(self, passes: Sequence[Pass], t_end: float, rng: np.random.Generator) -> np.ndarray:
        """Measurement times (J,) TU, strictly increasing, inside ``passes``, none after ``t_end``.

        passes : visibility passes (TU since the epoch); t_end : last admissible time, TU.
        """
        spans = sorted((float(p.start), min(float(p.end), float(t_end))) for p in passes)
        spans = [(a, b) for a, b in spans if a <= b]
        if not spans:
            return np.empty(0)
        origin = spans[0][0] if self.origin == "first-pass" else 0.0
        chunks = [self._plan_phase(ph, spans, origin, rng) for ph in self._phases]
        times = np.unique(np.concatenate(chunks)) if chunks else np.empty(0)
        return times[times <= t_end]

    def _plan_phase(self, ph: _Phase, spans, origin: float, rng) -> np.ndarray:
        if ph.rule == "off":
            return np.empty(0)
        w0, w1 = origin + ph.start, origin + ph.end
        stop = len(spans) if ph.to_pass is None else min(ph.to_pass, len(spans))
        segs = [(max(a, w0), min(b, w1)) for a, b in spans[ph.from_pass:stop]]
        segs = [(a, b) for a, b in segs if a <= b]
        if not segs:
            return np.empty(0)
        if ph.rule == "every" and ph.align == "clock":
            return self._clock(ph, segs, w0, rng)
        out = []
        for a, b in segs:
            if ph.rule == "every":
                out.append(self._cadence(ph, a, b, rng))
            else:
                out.append(self._consecutive(ph, a, b, rng))
        return np.concatenate(out)

    @staticmethod
    def _cadence(ph: _Phase, a: float, b: float, rng) -> np.ndarray:
        """Times a, a + dt, ... <= b (random dt when the phase has a spacing range)."""
        if ph.dt_max > ph.dt_min:
            n_max = int((b - a) / ph.dt_min + _EPS) + 1
            t = a + np.concatenate([[0.0], np.cumsum(ph.spacings(n_max - 1, rng))])
            return t[t <= b + _EPS]
        n = int((b - a) / ph.dt_min + 1e-9) + 1
        return np.minimum(a + np.arange(n) * ph.dt_min, b)

    @staticmethod
    def _consecutive(ph: _Phase, a: float, b: float, rng) -> np.ndarray:
        """``count`` consecutive times at a uniformly random place inside [a, b]."""
        offsets = np.concatenate([[0.0], np.cumsum(ph.spacings(ph.count - 1, rng))])
        room = (b - a) - offsets[-1]
        if room < 0:
            return a + offsets[offsets <= (b - a) + _EPS]
        return a + rng.uniform(0.0, room) + offsets

    @staticmethod
    def _clock(ph: _Phase, segs, w0: float, rng) -> np.ndarray:
        """One grid from the window start, keeping the times that fall in a visible segment."""
        last = segs[-1][1]
        if ph.dt_max > ph.dt_min:
            n_max = int((last - w0) / ph.dt_min + _EPS) + 1
            grid = w0 + np.concatenate([[0.0], np.cumsum(ph.spacings(n_max - 1, rng))])
        else:
            grid = w0 + np.arange(int((last - w0) / ph.dt_min + 1e-9) + 1) * ph.dt_min
        a = np.array([s[0] for s in segs])
        b = np.array([s[1] for s in segs])
        k = np.searchsorted(a, grid, side="right") - 1
        inside = (k >= 0) & (grid <= b[np.clip(k, 0, None)] + _EPS)
        return grid[inside]


class EverySchedule(PhasedSchedule):
    """Every ``interval_minutes`` while visible, between ``start_hours`` and ``end_hours``.

    Parameters
    ----------
    interval_minutes : float
        Spacing of the measurements, minutes.
    interval_max_minutes : float
        When larger than ``interval_minutes``, each spacing is drawn uniformly between the two,
        minutes (0 = fixed spacing).
    align : str
        ``"pass"`` restarts the cadence at every pass start; ``"clock"`` keeps one grid.
    start_hours, end_hours : float
        Window in which to measure, hours from the origin (the first pass by default).
    """

    def __init__(self, interval_minutes: float = 40.0, interval_max_minutes: float = 0.0,
                 align: str = "pass", start_hours: float = 0.0, end_hours: float = math.inf,
                 origin: str = "first-pass") -> None:
        self.interval_minutes = check_positive(self, "interval_minutes", interval_minutes)
        self.interval_max_minutes = check_nonnegative(self, "interval_max_minutes", interval_max_minutes)
        self.align = check_choice(self, "align", align, ("pass", "clock"))
        self.start_hours = start_hours
        self.end_hours = end_hours
        self.origin = check_choice(self, "origin", origin, ("first-pass", "epoch"))
        phase = {"rule": "every", "interval_minutes": interval_minutes, "align": align,
                 "start_hours": start_hours, "end_hours": end_hours}
        if interval_max_minutes:
            phase["interval_max_minutes"] = interval_max_minutes
        self._phases = self._parse([phase], "parameters")


class RandomConsecutiveSchedule(PhasedSchedule):
    """``count`` consecutive measurements at a random place in every pass from ``from_pass`` on.

    Parameters
    ----------
    count : int
        Consecutive measurements taken in each pass.
    interval_minutes : float
        Spacing of the measurements, minutes.
    interval_max_minutes : float
        When larger than ``interval_minutes``, each spacing is drawn uniformly between the two,
        minutes.
    from_pass : int
        First pass measured (0 = the first pass).
    """

    def __init__(self, count: int = 5, interval_minutes: float = 40.0,
                 interval_max_minutes: float = 60.0, from_pass: int = 0) -> None:
        self.count = check_int(self, "count", count, minimum=1)
        self.interval_minutes = check_positive(self, "interval_minutes", interval_minutes)
        self.interval_max_minutes = check_positive(self, "interval_max_minutes", interval_max_minutes)
        self.from_pass = check_int(self, "from_pass", from_pass, minimum=0)
        self.origin = "first-pass"
        phase = {"rule": "random-consecutive", "count": count, "interval_minutes": interval_minutes,
                 "interval_max_minutes": max(interval_max_minutes, interval_minutes),
                 "from_pass": from_pass}
        self._phases = self._parse([phase], "parameters")


class PaperExample1Schedule(PhasedSchedule):
    """Paper Example 1: the whole first pass every 40–60 min, then a few measurements per pass.

    The first pass is measured throughout with random spacing; every later pass gets ``count``
    random consecutive measurements, spaced the same way.

    Parameters
    ----------
    interval_minutes, interval_max_minutes : float
        Each spacing is drawn uniformly between these two, minutes.
    count : int
        Consecutive measurements taken in each pass after the first.
    """

    def __init__(self, interval_minutes: float = 40.0, interval_max_minutes: float = 60.0,
                 count: int = 5) -> None:
        self.interval_minutes = check_positive(self, "interval_minutes", interval_minutes)
        self.interval_max_minutes = check_positive(self, "interval_max_minutes", interval_max_minutes)
        self.count = check_int(self, "count", count, minimum=1)
        self.origin = "first-pass"
        spacing = {"interval_minutes": interval_minutes, "interval_max_minutes": interval_max_minutes}
        self._phases = self._parse([
            {"rule": "every", "to_pass": 1, **spacing},
            {"rule": "random-consecutive", "from_pass": 1, "count": count, **spacing},
        ], "parameters")


class PaperExample2Schedule(PhasedSchedule):
    """Paper Example 2: every 40 min for 33 h, a 10-day shutoff, then every 16 h when visible.

    Parameters
    ----------
    interval_minutes : float
        Spacing while visible during the initial phase, minutes.
    initial_hours : float
        Length of the initial phase, hours from the start of the first pass.
    shutoff_days : float
        Gap without measurements after the initial phase, days.
    final_interval_hours : float
        Spacing after the shutoff (one clock grid; a grid time is measured when the target is
        visible), hours.
    """

    def __init__(self, interval_minutes: float = 40.0, initial_hours: float = 33.0,
                 shutoff_days: float = 10.0, final_interval_hours: float = 16.0) -> None:
        self.interval_minutes = check_positive(self, "interval_minutes", interval_minutes)
        self.initial_hours = initial_hours
        self.shutoff_days = shutoff_days
        self.final_interval_hours = final_interval_hours
        self.origin = "first-pass"
        check_positive(self, "initial_hours", initial_hours)
        check_positive(self, "final_interval_hours", final_interval_hours)
        resume = initial_hours + 24.0 * check_nonnegative(self, "shutoff_days", shutoff_days)
        self._phases = self._parse([
            {"rule": "every", "interval_minutes": interval_minutes, "end_hours": initial_hours},
            {"rule": "every", "interval_minutes": 60.0 * final_interval_hours, "align": "clock",
             "start_hours": resume},
        ], "parameters")


class PaperExample3Schedule(PhasedSchedule):
    """Paper Example 3: every 40 min for 24 h, a 150-day shutoff, then every 40 min when visible.

    Parameters
    ----------
    interval_minutes : float
        Spacing while visible, minutes (both phases).
    initial_hours : float
        Length of the initial phase, hours from the start of the first pass.
    shutoff_days : float
        Gap without measurements after the initial phase, days.
    """

    def __init__(self, interval_minutes: float = 40.0, initial_hours: float = 24.0,
                 shutoff_days: float = 150.0) -> None:
        self.interval_minutes = check_positive(self, "interval_minutes", interval_minutes)
        self.initial_hours = initial_hours
        self.shutoff_days = shutoff_days
        self.origin = "first-pass"
        check_positive(self, "initial_hours", initial_hours)
        resume = initial_hours + 24.0 * check_nonnegative(self, "shutoff_days", shutoff_days)
        self._phases = self._parse([
            {"rule": "every", "interval_minutes": interval_minutes, "end_hours": initial_hours},
            {"rule": "every", "interval_minutes": interval_minutes, "start_hours": resume},
        ], "parameters")


@hookimpl
def cistrack_register(registry):
    registry.add("schedule", "phased", PhasedSchedule)
    registry.add("schedule", "every", EverySchedule)
    registry.add("schedule", "random-consecutive", RandomConsecutiveSchedule)
    registry.add("schedule", "paper-example-1", PaperExample1Schedule)
    registry.add("schedule", "paper-example-2", PaperExample2Schedule)
    registry.add("schedule", "paper-example-3", PaperExample3Schedule)
