"""The general tasking policy :class:`PhasedSchedule` (registered as schedule ``"phased"``):
phases with time windows, pass ranges and cadence rules (see :mod:`.schedules` for the syntax
and the presets built on it)."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from cistrack.interfaces.component import check_choice, check_int, check_nonnegative, check_positive
from cistrack.interfaces import Pass, Schedule
from cistrack.interfaces.limits import MAX_STEPS
from cistrack.units import TU_S

__all__ = ["PhasedSchedule", "RULES"]

RULES = ("every", "random-consecutive", "off")
_HOUR_TU = 3600.0 / TU_S
_MIN_TU = 60.0 / TU_S
_DAY_TU = 86400.0 / TU_S
_ALLOWED_KEYS = {"rule", "start_hours", "start_days", "end_hours", "end_days", "from_pass",
                 "to_pass", "interval_minutes", "interval_max_minutes", "align", "count"}
_EPS = 1e-12


@dataclass
class _Phase:
    """A validated phase (internal): ``rule``; window ``start``/``end`` TU from the origin; passes
    ``from_pass`` to ``to_pass`` (exclusive; None: all); spacing ``dt_min``..``dt_max`` TU;
    ``align`` ("pass" or "clock"); ``count`` for random-consecutive. ``names`` are the parameters
    that set its spacing and its count, for messages; ``values`` their given values."""

    rule: str
    start: float
    end: float
    from_pass: int
    to_pass: int | None
    dt_min: float
    dt_max: float
    align: str
    count: int
    names: tuple[str, str] = ("interval_minutes", "count")
    values: tuple[Any, Any] = (None, None)

    def spacings(self, n: int, rng: np.random.Generator) -> np.ndarray:
        if self.dt_max > self.dt_min:
            return rng.uniform(self.dt_min, self.dt_max, n)
        return np.full(n, self.dt_min)


def _dot(where: str) -> str:
    """``where`` and a dot before a key name, or nothing for a preset's own parameters."""
    return f"{where}." if where else ""


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
    # A phase's keys are named "phases[i].KEY"; a one-phase preset's phase (pname "parameters") is
    # made of the preset's own parameters, named "KEY" as the user wrote them.
    def _parse(self, phases: Any, pname: str, names: Sequence[tuple[str, str]] | None = None) -> list[_Phase]:
        """Validated phases; ``names`` give, per phase, the parameters that set its spacing and
        count when they are not the phase's own keys (presets)."""
        if not isinstance(phases, (list, tuple)) or not phases:
            self._fail(pname, phases, "must be a non-empty list of tables (one per phase)")
        out = []
        for i, p in enumerate(phases):
            own = pname == "parameters" and len(phases) == 1  # a one-phase preset's keys are its own parameters
            ph = self._parse_one(p, "" if own else f"{pname}[{i}]")
            ph.names = names[i] if names else (f"{pname}[{i}].interval_minutes", f"{pname}[{i}].count")
            ph.values = (p.get("interval_minutes"), p.get("count", 5))
            out.append(ph)
        return out

    def _parse_one(self, p: Any, where: str) -> _Phase:
        if not isinstance(p, dict):
            self._fail(where or "parameters", p, "must be a table with at least 'rule'")
        unknown = sorted(set(p) - _ALLOWED_KEYS)
        if unknown:
            self._fail(where or "parameters", p, f"unknown key(s) {unknown}; allowed: {sorted(_ALLOWED_KEYS)}")
        rule = check_choice(self, f"{_dot(where)}rule", p.get("rule"), RULES)
        start = self._time(p, where, "start", 0.0)
        end = self._time(p, where, "end", math.inf)
        if end <= start:
            self._fail(where or "parameters", p, "the phase must end after it starts")
        from_pass = check_int(self, f"{_dot(where)}from_pass", p.get("from_pass", 0), minimum=0)
        to_pass = p.get("to_pass", None)
        if to_pass is not None:
            to_pass = check_int(self, f"{_dot(where)}to_pass", to_pass, minimum=from_pass + 1)
        dt_min = dt_max = 0.0
        if rule != "off":
            if "interval_minutes" not in p:
                self._fail(where or "parameters", p, f"rule '{rule}' needs 'interval_minutes'")
            dt_min = check_positive(self, f"{_dot(where)}interval_minutes", p["interval_minutes"]) * _MIN_TU
            dt_max = dt_min
            if "interval_max_minutes" in p:
                hi = check_positive(self, f"{_dot(where)}interval_max_minutes", p["interval_max_minutes"])
                if hi * _MIN_TU < dt_min:
                    self._fail(f"{_dot(where)}interval_max_minutes", hi, "must be >= interval_minutes")
                dt_max = hi * _MIN_TU
        align = check_choice(self, f"{_dot(where)}align", p.get("align", "pass"), ("pass", "clock"))
        count = check_int(self, f"{_dot(where)}count", p.get("count", 5), minimum=1)
        return _Phase(rule, start, end, from_pass, to_pass, dt_min, dt_max, align, count)

    def _time(self, p: dict, where: str, which: str, default: float) -> float:
        h, d = p.get(f"{which}_hours"), p.get(f"{which}_days")
        if h is not None and d is not None:
            self._fail(where or "parameters", p, f"give '{which}_hours' or '{which}_days', not both")
        if h is None and d is None:
            return default
        key, value, unit = (f"{which}_hours", h, _HOUR_TU) if h is not None else (f"{which}_days", d, _DAY_TU)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value == math.inf:
            return math.inf
        return check_nonnegative(self, f"{_dot(where)}{key}", value) * unit

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
        self._check_count(spans, origin)
        chunks = [self._plan_phase(ph, spans, origin, rng) for ph in self._phases]
        times = np.unique(np.concatenate(chunks)) if chunks else np.empty(0)
        return times[times <= t_end]

    @staticmethod
    def _segments(ph: _Phase, spans, origin: float) -> list[tuple[float, float]]:
        """The parts of the passes ``spans`` that phase ``ph`` measures in."""
        w0, w1 = origin + ph.start, origin + ph.end
        stop = len(spans) if ph.to_pass is None else min(ph.to_pass, len(spans))
        segs = [(max(a, w0), min(b, w1)) for a, b in spans[ph.from_pass:stop]]
        return [(a, b) for a, b in segs if a <= b]

    def _check_count(self, spans, origin: float) -> None:
        """Refuse, before building them, more measurement times than a run may take as filter
        steps (:data:`~cistrack.interfaces.limits.MAX_STEPS`), naming the parameter of the
        phase that makes the most."""
        counts = []
        for ph in self._phases:
            segs = self._segments(ph, spans, origin) if ph.rule != "off" else []
            if not segs:
                counts.append((0.0, ph))
            elif ph.rule == "random-consecutive":
                counts.append((float(ph.count) * len(segs), ph))
            elif ph.align == "clock":
                counts.append(((segs[-1][1] - origin - ph.start) / ph.dt_min + 1, ph))
            else:
                counts.append((sum((b - a) / ph.dt_min + 1 for a, b in segs), ph))
        total = sum(n for n, _ in counts)
        if total > MAX_STEPS:
            n, ph = max(counts, key=lambda c: c[0])
            which = 1 if ph.rule == "random-consecutive" else 0
            name = ph.names[which]
            self._fail(name, getattr(self, name, ph.values[which]),
                       f"it would plan about {total:.3g} measurement times in {len(spans)} visibility "
                       f"pass{'' if len(spans) == 1 else 'es'} "
                       f"({sum(b - a for a, b in spans) * TU_S / 86400.0:.3g} days); at most {MAX_STEPS:,} are "
                       "allowed (each is a filter step): choose a " + ("smaller count" if which else "longer interval"))

    def _plan_phase(self, ph: _Phase, spans, origin: float, rng) -> np.ndarray:
        if ph.rule == "off":
            return np.empty(0)
        w0 = origin + ph.start
        segs = self._segments(ph, spans, origin)
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
