"""What a recording shows of maneuvers: the truth's burns, the detector's statistic and its
detections, and the burns the run estimated.

Logged by :class:`ManeuverMarks` for :mod:`.rerun_recorder` (entity paths; nothing of a kind
that a run lacks is logged, so a ballistic run without a detector records none of them):

==================================  ==========================================================
``maneuvers/truth``                 text: each truth burn ("burn: 1 m/s in-track (rtn-moon)") at its time
``world/truth/burns``               the truth burns in the 3-D scene: an arrow along the velocity jump
                                    at the burn's position (static)
``world/truth/burns/labels``        each burn's name, off the Earth–Moon line (static)
``series/nees/truth_burns/<k>``     a vertical (orange) line across the NEES panel at burn ``k``'s time
``series/maneuver/statistic``       the detector's statistic (-log10 p) at every update, its line broken
                                    between passes (:data:`STATISTIC_GAP_HOURS`)
``series/maneuver/threshold``       its threshold, a constant line beside it
``series/maneuver/truth_burns/<k>`` a vertical line across the statistic panel at burn ``k``'s time
``series/maneuver/detections``      a red diamond on the statistic at each update that raised a detection
``series/nees/detections``          the same on the (log10) NEES series
``series/maneuver/estimated_burns`` a green triangle at each estimated burn time (end of the run)
``maneuvers/detections``            text: each detection, its statistic and burn window
``maneuvers/estimates``             text at the end: each estimated burn, delta-v +- sigma, confirmed or not
==================================  ==========================================================

The truth and the estimates are logged on the ``utc`` timeline only (a burn is no step of the
filter); the detections at their update's step.
"""
from __future__ import annotations

import math
from datetime import datetime
from typing import Any

import numpy as np

from cistrack import units
from cistrack.lazy import LazyModule
from cistrack.units import LU_KM

from .run_extents import set_step_times, utc_at
from .run_series import nees_y_range

rr = LazyModule("rerun")

__all__ = ["ManeuverMarks", "STATISTIC", "THRESHOLD", "DETECTIONS", "NEES_DETECTIONS", "ESTIMATED_BURNS",
           "NEES_BURNS", "STATISTIC_BURNS", "TRUTH_LOG", "DETECTION_LOG", "ESTIMATE_LOG", "BURN_ARROWS",
           "BURN_LABELS", "BURN_LABEL_OFFSET_KM", "STATISTIC_COLOUR", "STATISTIC_GAP_HOURS", "burn_label_positions", "burn_text",
           "estimate_text"]

STATISTIC = "series/maneuver/statistic"
THRESHOLD = "series/maneuver/threshold"
DETECTIONS = "series/maneuver/detections"
NEES_DETECTIONS = "series/nees/detections"
ESTIMATED_BURNS = "series/maneuver/estimated_burns"
NEES_BURNS = "series/nees/truth_burns"
STATISTIC_BURNS = "series/maneuver/truth_burns"
TRUTH_LOG = "maneuvers/truth"
DETECTION_LOG = "maneuvers/detections"
ESTIMATE_LOG = "maneuvers/estimates"
BURN_ARROWS = "world/truth/burns"
BURN_LABELS = "world/truth/burns/labels"

STATISTIC_GAP_HOURS = 6.0
"""Updates further apart than this (between passes) are not joined by the statistic's line: the test
takes no value in between. A ``Clear`` logged at the earlier update's times (after its value) ends
the line there on every timeline."""

STATISTIC_COLOUR = (60, 130, 255)
THRESHOLD_COLOUR = (150, 150, 150)
DETECTION_COLOUR = (255, 50, 50)
BURN_COLOUR = (255, 140, 0)
"""The truth burns' colour: their lines on the series panels, their arrows and their log entries
(orange reads on the viewer's dark and light themes; white would vanish on the light one)."""
ESTIMATE_COLOUR = (40, 180, 80)

_POINT_STYLES = {DETECTIONS: (DETECTION_COLOUR, "detection", "diamond"),
                 NEES_DETECTIONS: (DETECTION_COLOUR, "detection", "diamond"),
                 ESTIMATED_BURNS: (ESTIMATE_COLOUR, "estimated burn", "up")}
"""Colour, legend name and marker of each point series."""

BURN_ARROW_KM = 30_000.0
"""Length of a truth burn's arrow in the 3-D scene (the system view spans about 450,000 km)."""


BURN_LABEL_OFFSET_KM = 60_000.0
"""How far a burn's name sits from its arrow, across the Earth–Moon line (scene y, km): the
system view shows that line from above with the Earth, Moon and L1..L5 labels on it, and a
label at a burn near the Moon would cover the Moon's (60,000 km is about 100 pixels there)."""


def burn_label_positions(origins_km: np.ndarray) -> np.ndarray:
    """Where the names of burns at ``origins_km`` (N, 3), km, scene frame, are drawn (N, 3):
    :data:`BURN_LABEL_OFFSET_KM` beyond each burn in y, on its side of the Earth–Moon line
    (the +y side for a burn on it)."""
    p = np.asarray(origins_km, dtype=float).reshape(-1, 3).copy()
    p[:, 1] += np.where(p[:, 1] < 0.0, -BURN_LABEL_OFFSET_KM, BURN_LABEL_OFFSET_KM)
    return p


def _finite(value: Any) -> float | None:
    """``value`` as a float when it is a finite real number (not a bool), else None."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def burn_text(impulse) -> str:
    """A truth burn in words: "truth burn: 1 m/s in-track (rtn-moon), at 3.620 d, |dv| 1 m/s"."""
    size = float(np.linalg.norm(impulse.dv)) * float(units.vu_to_kms(1.0)) * 1000.0
    name = impulse.label or "burn"
    return f"truth {name}, at {float(units.tu_to_days(impulse.t)):.3f} d, |dv| {size:.3g} m/s"


def estimate_text(m: dict) -> str:
    """A ``summary.maneuvers`` entry in words: burn time, delta-v +- sigma, confirmed or not."""
    t_burn, t_det = _finite(m.get("t_burn_days")), _finite(m.get("t_days"))
    dv, sigma = _finite(m.get("delta_v_ms")), _finite(m.get("delta_v_sigma_ms"))
    when = f"estimated burn at {t_burn:.3f} d" if t_burn is not None else "burn time not estimated"
    sig_t = _finite(m.get("t_burn_sigma_days"))
    if t_burn is not None and sig_t is not None:
        when += f" ± {24.0 * sig_t:.2g} h"  # a burn pinned between two updates: minutes, not 0.000 d
    detected = f" (detected at {t_det:.3f} d)" if t_det is not None else ""
    size = "no delta-v estimate"
    if dv is not None:
        size = f"delta-v {dv:.3g} ± {sigma:.2g} m/s" if sigma is not None else f"delta-v {dv:.3g} m/s"
    verdict = "confirmed" if m.get("confirmed") else ("not estimated" if m.get("confirmed") is None else "unconfirmed")
    return f"{when}{detected}: {size}, {verdict}"


class ManeuverMarks:
    """The maneuver entities of one run's recording (module docstring).

    ``run``: the run's context (``truth_impulses``, ``maneuvers``); ``view``: the scene's
    :class:`~.view_frame.ViewFrame`; ``epoch``: the scenario epoch (datetime, UTC).
    """

    def __init__(self, run, view, epoch: datetime) -> None:
        self.burns = list(getattr(run, "truth_impulses", None) or ())
        self.watch = getattr(run, "maneuvers", None)
        self.view, self.epoch = view, epoch
        self.threshold = _finite(getattr(getattr(self.watch, "detector", None), "threshold", None))
        self.top = 2.0 * self.threshold if self.threshold is not None else 1.0
        self._styled: set[str] = set()
        self._last: tuple[int, int, float] | None = None  # (event, step, t TU) of the last statistic

    @property
    def watching(self) -> bool:
        """Whether the run watches for maneuvers (its updates carry the statistic)."""
        return self.watch is not None

    def _utc(self, t_tu: float) -> datetime:
        return utc_at(self.epoch, t_tu)

    # -- run start --------------------------------------------------------------------------------
    def log_start(self, rec, run) -> None:
        """Line styles, and each truth burn: its text, its vertical lines, its arrow."""
        if self.watching:
            rec.log(STATISTIC, rr.SeriesLines(colors=[STATISTIC_COLOUR], names=["statistic"], widths=[2.0]),
                    static=True)
            rec.log(THRESHOLD, rr.SeriesLines(colors=[THRESHOLD_COLOUR], names=["threshold"], widths=[1.5]),
                    static=True)
        if not self.burns:
            return
        self._log_arrows(rec, run)
        lo, hi = nees_y_range()
        for k, imp in enumerate(self.burns, start=1):
            rec.reset_time()
            rec.set_time("utc", timestamp=self._utc(imp.t))
            rec.log(TRUTH_LOG, rr.TextLog(burn_text(imp), level="INFO", color=BURN_COLOUR))
            lines = [(f"{NEES_BURNS}/{k}", (lo, hi))]
            if self.watching:
                lines.append((f"{STATISTIC_BURNS}/{k}", (0.0, self.top)))
            for entity, ys in lines:
                rec.log(entity, rr.SeriesLines(colors=[BURN_COLOUR], names=[f"truth burn {k}"], widths=[1.5],
                                               aggregation_policy="Off"), static=True)
                for y in ys:  # two values at one time: a vertical line
                    rec.log(entity, rr.Scalars(float(y)))
        rec.reset_time()

    def _log_arrows(self, rec, run) -> None:
        """Each truth burn as an arrow along its velocity jump at its position (km, static)."""
        origins, vectors, labels = [], [], []
        for imp in self.burns:
            state = run.truth_at(float(imp.t))
            if state is None:
                continue
            before = np.asarray(state, dtype=float).reshape(6)
            after = before.copy()
            after[3:] += imp.dv
            s = self.view.states(np.stack([before, after]), float(imp.t))
            jump = s[1, 3:] - s[0, 3:]
            norm = float(np.linalg.norm(jump))
            if not norm > 0.0:
                continue
            origins.append(s[0, :3] * LU_KM)
            vectors.append(jump / norm * BURN_ARROW_KM)
            labels.append(imp.label or "burn")
        if origins:
            rec.log(BURN_ARROWS, rr.Arrows3D(origins=origins, vectors=vectors, colors=[BURN_COLOUR],
                                             radii=rr.Radius.ui_points(2.5)), static=True)
            rec.log(BURN_LABELS, rr.Points3D(burn_label_positions(np.array(origins)), labels=labels,
                                             show_labels=True, colors=[BURN_COLOUR],
                                             radii=rr.Radius.ui_points(1.0)), static=True)

    # -- each step with metrics -------------------------------------------------------------------
    def log_step(self, rec, step, nees_log10: float | None, event: int) -> None:
        """The statistic and its threshold at an update; a detection's markers and text
        (``nees_log10``: the step's plotted log10 NEES, None without one). Call with the step's
        time set (``event``: its value on the ``event`` timeline)."""
        metrics = step.metrics or {}
        stat = _finite(metrics.get("maneuver_statistic"))
        if stat is None:
            return
        self._break_after_gap(rec, step, event)
        rec.log(STATISTIC, rr.Scalars(stat))
        self.top = max(self.top, stat)
        if self.threshold is not None:
            rec.log(THRESHOLD, rr.Scalars(self.threshold))
        if _finite(metrics.get("maneuver_detected")) != 1.0:
            return
        self._point(rec, DETECTIONS, stat)
        if nees_log10 is not None:
            self._point(rec, NEES_DETECTIONS, nees_log10)
        rec.log(DETECTION_LOG, rr.TextLog(self._detection_text(step, stat), level="WARN",
                                          color=DETECTION_COLOUR))

    def _break_after_gap(self, rec, step, event: int) -> None:
        """End the statistic's line at the last update when this one comes more than
        :data:`STATISTIC_GAP_HOURS` after it (the times set again to this step's afterwards)."""
        last, self._last = self._last, (int(event), int(step.index), float(step.t))
        if last is None or float(units.tu_to_days(float(step.t) - last[2])) * 24.0 <= STATISTIC_GAP_HOURS:
            return
        set_step_times(rec, last[0], last[1], self._utc(last[2]))
        rec.log(STATISTIC, rr.Clear(recursive=False))
        set_step_times(rec, event, step.index, self._utc(step.t))

    def _detection_text(self, step, stat: float) -> str:
        t = float(step.t)
        found = [d for d in getattr(self.watch, "detections", None) or () if abs(float(d.t) - t) < 1e-9]
        text = f"maneuver detected at {float(units.tu_to_days(t)):.3f} d: statistic {stat:.3g}"
        if not found:
            return text
        d = found[-1]
        if self.threshold is None:
            self.threshold = _finite(d.threshold)
        lo, hi = (_finite(b) for b in d.t_burn_bounds)
        text += f" > threshold {float(d.threshold):.3g}"
        if lo is not None and hi is not None:
            text += (f"; burn between {float(units.tu_to_days(lo)):.3f} and "
                     f"{float(units.tu_to_days(hi)):.3f} d")
        return text + (f" ({d.detector})" if d.detector else "")

    def _point(self, rec, entity: str, value: float) -> None:
        """A marker of the point series ``entity`` (a detection or an estimated burn), its style
        logged with its first point: a run without any has no such entity."""
        if entity not in self._styled:
            self._styled.add(entity)
            colour, name, marker = _POINT_STYLES[entity]
            rec.log(entity, rr.SeriesPoints(colors=[colour], names=[name], markers=[marker], marker_sizes=[6.0]),
                    static=True)
        rec.log(entity, rr.Scalars(float(value)))

    # -- run end ----------------------------------------------------------------------------------
    def log_finish(self, rec, summary) -> None:
        """Each estimated burn (``summary.maneuvers``): its text and its marker at its time; the
        statistic panel's burn lines stretched to the largest statistic."""
        found = summary.get("maneuvers") if isinstance(summary, dict) else getattr(summary, "maneuvers", None)
        estimates = [m for m in found or () if isinstance(m, dict)]
        for m in estimates:
            t_days = _finite(m.get("t_burn_days"))
            t_days = t_days if t_days is not None else _finite(m.get("t_days"))
            if t_days is None:
                continue
            rec.reset_time()
            rec.set_time("utc", timestamp=self._utc(float(units.days_to_tu(t_days))))
            rec.log(ESTIMATE_LOG, rr.TextLog(estimate_text(m), level="INFO" if m.get("confirmed") else "WARN",
                                             color=ESTIMATE_COLOUR))
            if self.watching and m.get("confirmed"):
                self._point(rec, ESTIMATED_BURNS, self.threshold if self.threshold is not None else 0.0)
        if self.watching:
            for k, imp in enumerate(self.burns, start=1):
                rec.reset_time()
                rec.set_time("utc", timestamp=self._utc(imp.t))
                rec.log(f"{STATISTIC_BURNS}/{k}", rr.Scalars(float(self.top)))
        rec.reset_time()
