"""The windowed sequential test both built-in maneuver detectors share.

Each update gives one chi-square-distributed contribution ``c`` with ``dof`` degrees of freedom
when the filter is consistent (the NIS with m dof; or -2 ln p, with 2 dof, of a tail
probability p). The test sums the contributions of the last ``window`` updates (a sum of
independent chi-squares is chi-square with the summed dof) and also tests the newest one alone;
each is expressed as a surprise, -log10 of its tail probability, and compared with
-log10(false_alarm). A detection further needs at least ``min_surprising`` of the window's
updates each individually surprising (tail probability below ``update_level``), so that one
gross outlier among good measurements does not fire by itself, with one exception: a *gross*
update (tail probability below ``false_alarm``) that comes at least ``gap_hours`` after the update
before it (the first of a pass) fires alone. A burn in the gap shows first there, and a filter
whose prior is wide after the gap may absorb it at that update, leaving the rest of the pass
consistent (on ``example-1-burn``'s 1 m/s burn, three runs in 30 whose first update after the
burn had a surprise of 7.6-11.6 waited a pass for a second surprising update). ``warmup`` updates after
:meth:`reset` are judged but never fire and do not enter the window (the filter settles after
its IOD). After a detection the window is cleared: the next test starts on new evidence only.

The burn's interval, ``Detection.t_burn_bounds = (t_lo, t)``: ``t_lo`` is the time of the update
before the window's first surprising one, or before an earlier *gross* update (tail probability
below ``false_alarm``) among the last ``LOOKBACK_WINDOWS`` windows' worth of updates since the
previous detection, whichever is earlier. A filter whose prior is wide (after a gap between
passes) absorbs much of a burn at the first update after it: that update is gross, the next
ones may look consistent until the error grows again, and the detection comes passes later;
the look-back keeps the burn inside the bounds then.
"""
from __future__ import annotations

import math
from abc import abstractmethod
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

from cistrack import units
from cistrack.errors import FilterError, MeasurementError, ParameterError
from cistrack.interfaces.component import check_int, check_range
from cistrack.interfaces.maneuvers import Detection, ManeuverDetector
from cistrack.model.measurement import Measurement, StackedMeasurement
from cistrack.numerics.special_functions import gamma_q

__all__ = ["SequentialDetector", "chi2_log10_sf", "measurement_group", "LOOKBACK_WINDOWS"]

_LN10 = math.log(10.0)

_MAX_CONTRIBUTION = 1e12
"""Contributions are capped here (NIS 1e12: a surprise of ~2e11), so the statistic stays finite."""

LOOKBACK_WINDOWS = 5
"""How many windows' worth of past updates a gross update may widen ``t_burn_bounds`` over."""


def chi2_log10_sf(x: float, dof: float) -> float:
    """log10 of the chi-square tail probability P(X >= x), X ~ chi2(dof), finite even where the
    probability underflows (then from the leading term of the upper incomplete gamma function,
    Gamma(s, y) ~ y^(s-1) e^-y)."""
    if not x > 0:
        return 0.0
    s, y = 0.5 * dof, 0.5 * x
    p = gamma_q(s, y)
    if p > 1e-290:
        return math.log10(p)
    return (-y + (s - 1.0) * math.log(y) - math.lgamma(s)) / _LN10


def measurement_group(measurements) -> list[Measurement]:
    """The measurements of one update as a list: a sequence of :class:`Measurement`, one
    :class:`Measurement`, or a :class:`StackedMeasurement` (its parts)."""
    if isinstance(measurements, StackedMeasurement):
        return list(measurements.parts)
    if isinstance(measurements, Measurement):
        return [measurements]
    group = list(measurements)
    if not group:
        raise MeasurementError("a maneuver detector needs at least one measurement per update, got none")
    return group


@dataclass(frozen=True)
class _Entry:
    """One update in the window."""

    t: float
    t_before: float     # the previous update's time (t itself for the first update after reset)
    c: float            # chi-square contribution
    dof: float
    surprising: bool    # tail probability below update_level
    gross: bool         # tail probability below false_alarm
    after_gap: bool     # at least gap_hours after the update before it


class SequentialDetector(ManeuverDetector):
    """Base of the built-in detectors: the windowed test of the module docstring. A subclass
    validates its parameters with :meth:`_init_test` and gives each update's contribution in
    :meth:`_contribution`."""

    window: int
    false_alarm: float
    warmup: int
    min_surprising: int
    update_level: float
    gap_hours: float

    def _init_test(self, window: int, false_alarm: float, warmup: int, min_surprising: int,
                   update_level: float, gap_hours: float = 6.0) -> None:
        self.window = check_int(self, "window", window, minimum=1, maximum=1000)
        self.false_alarm = check_range(self, "false_alarm", false_alarm, 0.0, 0.5, lo_open=True)
        self.warmup = check_int(self, "warmup", warmup, minimum=0)
        self.min_surprising = check_int(self, "min_surprising", min_surprising, minimum=1)
        if self.min_surprising > self.window:
            raise ParameterError(f"{self._label()}: parameter 'min_surprising' = {min_surprising!r} is invalid: "
                                 f"must be <= window ({self.window}); the surprising updates are counted in the window")
        self.update_level = check_range(self, "update_level", update_level, 0.0, 1.0, lo_open=True)
        if self.update_level < self.false_alarm:
            raise ParameterError(f"{self._label()}: parameter 'update_level' = {update_level!r} is invalid: must be "
                                 f">= false_alarm ({self.false_alarm}); it is the looser per-update level")
        off = isinstance(gap_hours, float) and gap_hours == math.inf
        self.gap_hours = math.inf if off else check_range(self, "gap_hours", gap_hours, 0.0, math.inf, lo_open=True)
        self.reset()

    def reset(self) -> None:
        self._entries: deque[_Entry] = deque(maxlen=self.window)
        self._recent: deque[_Entry] = deque(maxlen=LOOKBACK_WINDOWS * self.window)
        self._seen = 0
        self._last_t: float | None = None

    @abstractmethod
    def _contribution(self, t: float, prior, group: list[Measurement], sensor) -> tuple[float, float, dict]:
        """(c, dof, extra): a chi2(dof) contribution for a consistent filter, and values for
        :attr:`Detection.extra`."""

    @property
    def threshold(self) -> float:
        """The statistic's threshold, -log10(false_alarm)."""
        return -math.log10(self.false_alarm)

    def observe(self, t: float, prior, measurements: Sequence[Measurement], sensor) -> tuple[float, Detection | None]:
        t = float(t)
        if not math.isfinite(t) or (self._last_t is not None and t < self._last_t):
            raise MeasurementError(f"{self._label()}: updates must come in time order with finite times; got t = {t!r} "
                                   f"after {self._last_t!r} (call reset() for a new run)")
        c, dof, extra = self._contribution(t, prior, measurement_group(measurements), sensor)
        if not c >= 0.0:
            raise FilterError(f"{self._label()}: the update at t = {t!r} gives the test contribution {c!r}; the prior "
                              "or the measurements are not finite, or the predicted covariance is not positive definite")
        c = min(float(c), _MAX_CONTRIBUTION)
        single = -chi2_log10_sf(c, dof)
        before = t if self._last_t is None else self._last_t
        self._last_t = t
        self._seen += 1
        if self._seen <= self.warmup:
            return single, None
        after_gap = float(units.tu_to_days(t - before)) * 24.0 >= self.gap_hours
        entry = _Entry(t, before, c, dof, single > -math.log10(self.update_level), single >= self.threshold, after_gap)
        self._entries.append(entry)
        self._recent.append(entry)
        total_c = sum(e.c for e in self._entries)
        total_dof = sum(e.dof for e in self._entries)
        statistic = max(single, -chi2_log10_sf(total_c, total_dof))
        enough = sum(e.surprising for e in self._entries) >= self.min_surprising or (entry.gross and entry.after_gap)
        if statistic < self.threshold or not enough:
            return statistic, None
        first = next(e for e in self._entries if e.surprising)
        t_lo = min([first.t_before] + [e.t_before for e in self._recent if e.gross])
        extra = dict(extra, window_sum=total_c, window_dof=total_dof, window_updates=len(self._entries),
                     update_surprise=single)
        det = Detection(t=t, statistic=statistic, threshold=self.threshold, detector=self.registry_name or type(self).__name__,
                        t_burn_bounds=(t_lo, t), extra=extra)
        self._entries.clear()
        self._recent.clear()
        return statistic, det
