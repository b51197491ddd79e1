"""An object's observations split into arcs that one orbit each explains.

Two rules, applied in this order:

1. **Long gaps.** Observations more than :data:`LONG_GAP_DAYS` (30 days) apart belong to
   different arcs, always. Such a gap misses a whole lunation (the synodic month is 29.5 days):
   a cislunar orbit (periods of 1-4 weeks: the 9:2 NRHO 6.6 days, a 2:1 DRO 14.8 days,
   translunar orbits up to the Moon's 27.3 days) has passed at least one perigee or perilune, and
   refitting across it is what the issue calls "one fit over all of it". Shorter pauses, such as
   the bright Moon's (a week or more for an object that stays near the Moon in the sky), are left
   to rule 2, which tests them: in the public astrometry of 2025-010D (development subset)
   2026-04 and 2026-05 are 22.5 days apart, and one orbit explains both.
2. **Broken links.** Inside such an arc, observation groups more than :data:`LINK_GAP_DAYS`
   (3 days: more than a missed night or two) apart are joined one at a time, latest first, when
   the fit of what is joined so far predicts the earlier group within its predicted covariance
   (:mod:`cistrack.fitting.residual_ladder`: the median of the groups' per-observation miss in
   sigmas within the 1e-3 bound); a group it misses, or that it cannot predict (the orbit hits a
   body, the covariance spreads over degrees), starts another arc. Nights closer than 3 days are
   not tested: a fit over them that no orbit explains does not converge or leaves large
   residuals, and says so.

``fit.arcs`` (:func:`arc_choice`) chooses what is fitted: ``latest`` (default: the arc a user
predicts from; the others are reported as a residual ladder), ``each`` (every arc on its own) or
``all`` (one fit over every observation).
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any, Callable

import numpy as np

from cistrack.errors import CistrackError, ConfigError, quoted
from cistrack.model.measurement import MeasurementSet
from cistrack.units import TU_S, leap_seconds, seconds_to_tu, tu_to_days, tu_to_utc, utc_to_tu

__all__ = ["ArcSpan", "LinkedArc", "ArcSettings", "observation_groups", "long_gap_arcs", "link_latest_arc",
           "arc_choice", "arc_settings", "arc_sets", "in_time_base", "ARC_CHOICES", "ARC_KEYS", "LONG_GAP_DAYS",
           "LINK_GAP_DAYS"]

LONG_GAP_DAYS = 30.0
"""Observations farther apart than this (days) are always different arcs (module docstring)."""
LINK_GAP_DAYS = 3.0
"""Groups farther apart than this (days) are joined only when one orbit explains both."""
ARC_CHOICES = ("latest", "each", "all")
"""Values of ``fit.arcs``: fit the latest arc, each arc on its own, or all observations at once."""
ARC_KEYS = ("arcs", "arc_gap_days", "link_gap_days")
"""The ``fit.*`` keys :func:`arc_settings` takes."""


@dataclass(frozen=True)
class ArcSpan:
    """Observations of one arc (or one group of an arc).

    rows : (n,) int            rows of the measurement set, increasing
    start, end : float         times of its first and last observation, TU
    gap_before_days : float    days since the previous span's last observation (inf: the first)
    """

    rows: np.ndarray
    start: float
    end: float
    gap_before_days: float

    @property
    def n(self) -> int:
        return int(self.rows.size)

    @property
    def days(self) -> float:
        """Length of the span, days."""
        return float(tu_to_days(self.end - self.start))


def _spans(times: np.ndarray, gap_days: float, rows: np.ndarray | None = None) -> list[ArcSpan]:
    rows = np.arange(times.size) if rows is None else rows
    t = times[rows]
    gaps = tu_to_days(np.diff(t))
    cuts = np.nonzero(gaps > gap_days)[0] + 1
    out = []
    for part in np.split(np.arange(rows.size), cuts):
        before = float(gaps[part[0] - 1]) if part[0] > 0 else float("inf")
        out.append(ArcSpan(rows[part], float(t[part[0]]), float(t[part[-1]]), before))
    return out


def observation_groups(times: Any, gap_days: float = LINK_GAP_DAYS) -> list[ArcSpan]:
    """Groups of observations separated by more than ``gap_days`` days; ``times`` (K,) TU,
    non-decreasing. Raises ConfigError for a gap that is not a positive number."""
    if isinstance(gap_days, bool) or not isinstance(gap_days, (int, float)) or not gap_days > 0:
        raise ConfigError(f"arc gap {gap_days!r}: must be a positive number of days")
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.size == 0:
        return []
    return _spans(t, float(gap_days))


def long_gap_arcs(times: Any, long_gap_days: float = LONG_GAP_DAYS) -> list[ArcSpan]:
    """Arcs by rule 1 alone: observations (K,) TU split where they are more than
    ``long_gap_days`` apart (no fit needed: the integrator runs the filter on the latest)."""
    return observation_groups(times, long_gap_days)


@dataclass
class LinkedArc:
    """The latest arc after rule 2.

    arc : ArcSpan            the observations the fit uses (the groups joined to the latest)
    fit : FitResult          the fit over them
    earlier : list[ArcSpan]  the groups of the long-gap arc left out, oldest first (a broken link
                             before the first of them), then nothing else
    rungs : list             the residual-ladder rungs of the tested links, latest first; the last
                             one the broken link when there is one
    """

    arc: ArcSpan
    fit: Any
    earlier: list
    rungs: list


def _joined(a: ArcSpan, b: ArcSpan) -> ArcSpan:
    return ArcSpan(np.concatenate([a.rows, b.rows]), a.start, b.end, a.gap_before_days)


def link_latest_arc(dynamics, sensor, measurements: MeasurementSet, fit, refit: Callable,
                    link_gap_days: float = LINK_GAP_DAYS) -> LinkedArc:
    """Rule 2 on ``measurements`` (one long-gap arc, K rows, TU), given ``fit`` (a FitResult) of
    its latest group (the rows after its last gap longer than ``link_gap_days``).

    ``refit(subset: MeasurementSet, start: FitResult) -> FitResult`` fits the joined rows from
    the previous fit (e.g. ``fit_orbit(dynamics, sensor, subset, start.state, start.epoch,
    options=...)``); a join whose refit raises or does not converge is a broken link too.
    """
    from cistrack.fitting.residual_ladder import ladder_rung

    groups = observation_groups(measurements.times, link_gap_days)
    arc, rungs = groups[-1], []
    for k in range(len(groups) - 2, -1, -1):
        rung = ladder_rung(fit, dynamics, sensor, measurements, groups[k])
        rungs.append(rung)
        if rung.verdict != "consistent":
            return LinkedArc(arc, fit, groups[:k + 1], rungs)
        joined = _joined(groups[k], arc)
        try:
            again = refit(measurements.subset(joined.rows), fit)
        except CistrackError:
            again = None
        if again is None or not again.converged:
            rungs[-1] = rung.broken("the fit over both arcs does not converge")
            return LinkedArc(arc, fit, groups[:k + 1], rungs)
        arc, fit = joined, again
    return LinkedArc(arc, fit, [], rungs)


def arc_choice(value: Any) -> str:
    """``fit.arcs`` checked: one of :data:`ARC_CHOICES`; ConfigError naming the key otherwise."""
    if value not in ARC_CHOICES:
        raise ConfigError(f"--set fit.arcs={quoted(value)}: must be one of {', '.join(ARC_CHOICES)} (latest: fit the "
                          "latest arc and report the others' misses; each: fit every arc on its own; all: one fit "
                          "over every observation)")
    return str(value)


def arc_sets(measurements: MeasurementSet, choice: str,
             long_gap_days: float = LONG_GAP_DAYS) -> list[MeasurementSet]:
    """The measurement sets to fit for ``fit.arcs=choice``: the latest long-gap arc, every one
    (oldest first) or all rows at once (each a subset of ``measurements``, same time base)."""
    if arc_choice(choice) == "all":
        return [measurements]
    arcs = long_gap_arcs(measurements.times, long_gap_days)
    chosen = arcs[-1:] if choice == "latest" else arcs
    return [measurements.subset(a.rows) for a in chosen]


@dataclass(frozen=True)
class ArcSettings:
    """``fit.arcs`` (one of :data:`ARC_CHOICES`), ``fit.arc_gap_days`` (rule 1, days) and
    ``fit.link_gap_days`` (rule 2, days; at most ``arc_gap_days``)."""

    arcs: str = "latest"
    arc_gap_days: float = LONG_GAP_DAYS
    link_gap_days: float = LINK_GAP_DAYS


def _days_key(table: dict, key: str, default: float) -> float:
    v = table.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < float("inf"):
        raise ConfigError(f"--set fit.{key}={v!r}: must be a positive number of days")
    return float(v)


def arc_settings(table: dict[str, Any]) -> tuple[ArcSettings, dict[str, Any]]:
    """(the arc settings, the other keys) of a ``fit.*`` table; ConfigError naming the key."""
    rest = {k: v for k, v in table.items() if k not in ARC_KEYS}
    arcs = arc_choice(table.get("arcs", "latest"))
    long_gap = _days_key(table, "arc_gap_days", LONG_GAP_DAYS)
    link_gap = _days_key(table, "link_gap_days", LINK_GAP_DAYS)
    if link_gap > long_gap:
        raise ConfigError(f"--set fit.link_gap_days={link_gap:g}: must not exceed fit.arc_gap_days ({long_gap:g})")
    return ArcSettings(arcs, long_gap, link_gap), rest


def in_time_base(measurements: MeasurementSet, epoch: datetime, new_epoch: datetime) -> MeasurementSet:
    """``measurements`` with times (TU elapsed since ``epoch``) counted from ``new_epoch`` instead
    (earlier arcs get negative times in a scenario that starts at the latest).

    A time read from a UTC label (to the microsecond) is moved as its label's clock time since
    ``epoch`` minus the clock shift, plus the leap seconds between ``new_epoch`` and the label: no
    leap second in between gives the same bits whatever leap seconds lie between ``epoch`` and
    the label. Other times are moved by the elapsed time between the epochs."""
    shift = float(seconds_to_tu((new_epoch - epoch).total_seconds()))
    ms = measurements
    elapsed_shift = utc_to_tu(epoch, new_epoch)
    labels = [_label_of(epoch, float(t)) for t in ms.times]
    moved = np.array([t - elapsed_shift if when is None else _moved(epoch, new_epoch, when, shift)
                      for t, when in zip(ms.times, labels)], dtype=float).reshape(np.shape(ms.times))
    return MeasurementSet(moved, ms.values, ms.sigmas, ms.names, dict(ms.meta), ms.sites, ms.kinds,
                          dict(ms.site_table))


def _label_of(epoch: datetime, t: float) -> datetime | None:
    """The UTC label (whole microseconds) a reader turned into ``t`` (TU since ``epoch``), None
    when no label gives exactly ``t``."""
    near = tu_to_utc(epoch, t)
    for when in (near, near - _MICROSECOND, near + _MICROSECOND):
        if utc_to_tu(epoch, when) == t:
            return when
    return None


def _moved(epoch: datetime, new_epoch: datetime, when: datetime, shift: float) -> float:
    """TU from ``new_epoch`` to the label ``when``: the clock time since ``epoch`` less the clock
    ``shift``, plus the leap seconds between ``new_epoch`` and ``when`` if any."""
    t = (when - epoch).total_seconds() / TU_S - shift
    leap = leap_seconds(new_epoch, when)
    return t if leap == 0.0 else t + leap / TU_S


_MICROSECOND = timedelta(microseconds=1)
