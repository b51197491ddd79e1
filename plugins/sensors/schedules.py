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

import math

from cistrack.interfaces.component import check_choice, check_int, check_nonnegative, check_positive
from cistrack.api import hookimpl

from .phased_schedule import RULES, PhasedSchedule

__all__ = ["PhasedSchedule", "EverySchedule", "RandomConsecutiveSchedule",
           "PaperExample1Schedule", "PaperExample2Schedule", "PaperExample3Schedule", "RULES"]

_NAMES = ("interval_minutes", "count")
"""The preset parameters that set a phase's spacing and count (for messages)."""


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
        self._phases = self._parse([phase], "parameters", [_NAMES])


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
        self._phases = self._parse([phase], "parameters", [_NAMES])


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
        ], "parameters", [_NAMES, _NAMES])


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
        ], "parameters", [_NAMES, ("final_interval_hours", "count")])


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
        ], "parameters", [_NAMES, _NAMES])


@hookimpl
def cistrack_register(registry):
    registry.add("schedule", "phased", PhasedSchedule)
    registry.add("schedule", "every", EverySchedule)
    registry.add("schedule", "random-consecutive", RandomConsecutiveSchedule)
    registry.add("schedule", "paper-example-1", PaperExample1Schedule)
    registry.add("schedule", "paper-example-2", PaperExample2Schedule)
    registry.add("schedule", "paper-example-3", PaperExample3Schedule)
