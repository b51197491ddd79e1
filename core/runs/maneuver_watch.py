"""A run's maneuver watch: the detector at every update, the response, the delta-v estimate.

At each update step the run hands the watch the prior and the measurements before the filter takes
them (:meth:`ManeuverWatch.before_update`). The scenario's detector (``[maneuvers] detector``)
judges them; on a detection the response (``[maneuvers] response``, default none) may hand back a
widened cloud, from which the filter starts again before it takes the measurements. The watch keeps
each update's posterior mean (:meth:`after_update`), so that at the end of the run
(:meth:`records`) each detection's burn is estimated by least squares: the measurements of
:data:`PRE_DAYS` before the suspect interval and :data:`POST_DAYS` after the detection, the state
at the interval's start (from the posterior there) and an impulsive delta-v at one of
:data:`CANDIDATES` times across the interval as unknowns
(:func:`cistrack.least_squares.impulse_fit.fit_impulse`), tested against the same arc without a
burn (:func:`~cistrack.least_squares.impulse_fit.burn_evidence`): ``confirmed``.

The metric stage ``maneuvers`` (:class:`ManeuverMetric`) writes each update's test statistic
(``maneuver_statistic``) and whether it raised a detection (``maneuver_detected``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import PropagationError
from cistrack.interfaces.maneuvers import Detection, ManeuverDetector, ManeuverResponse
from cistrack.interfaces.metric import StepMetric
from cistrack.least_squares.errors import FitError
from cistrack.least_squares.options import FitOptions

__all__ = ["ManeuverWatch", "ManeuverMetric", "PRE_DAYS", "POST_DAYS", "CANDIDATES"]

PRE_DAYS = 2.0
"""Days of measurements before the suspect interval in the delta-v estimate."""
POST_DAYS = 2.0
"""Days of measurements after the detection in the delta-v estimate."""
CANDIDATES = 5
"""Burn times tried across the suspect interval."""


@dataclass
class _Posterior:
    t: float
    mean: np.ndarray


@dataclass
class ManeuverWatch:
    """The detector and response of one run, and what they saw (module docstring)."""

    detector: ManeuverDetector
    response: ManeuverResponse | None = None
    estimate: bool = True
    rng: Any = None
    filter_rng: Any = None
    say: Any = None
    detections: list[Detection] = field(default_factory=list)
    statistic: float = float("nan")
    fired: bool = False
    posteriors: list[_Posterior] = field(default_factory=list)

    def start(self) -> None:
        self.detector.reset()
        self.detections.clear()
        self.posteriors.clear()

    def before_update(self, ctx: Any, t: float, prior: Any, measurements: tuple) -> Any:
        """The detector's verdict on ``measurements`` at ``t`` (TU) under ``prior``; returns the
        response's cloud (the filter starts again from it) or None."""
        self.statistic, detection = self.detector.observe(t, prior, measurements, ctx.sensor)
        self.fired = detection is not None
        if detection is None:
            return None
        if not detection.detector:
            detection.detector = self.detector.registry_name or type(self.detector).__name__
        self.detections.append(detection)
        if self.response is None:
            return None
        return self.response.respond(detection, prior, ctx.dynamics, self.rng)

    def after_update(self, t: float, belief: Any) -> None:
        """Keep the posterior mean (6,) at ``t`` (TU)."""
        mean = np.asarray(belief.mixture.mean, dtype=float)
        if np.all(np.isfinite(mean)):
            self.posteriors.append(_Posterior(float(t), mean.copy()))

    def records(self, ctx: Any) -> list[dict[str, Any]]:
        """``summary.maneuvers``: one entry per detection (:func:`_record`)."""
        say = self.say or (lambda m: None)
        out = []
        for k, d in enumerate(self.detections):
            nxt = self.detections[k + 1].t_burn_bounds[0] if k + 1 < len(self.detections) else np.inf
            fit = self._estimate(ctx, d, nxt, say) if self.estimate else None
            out.append(_record(d, fit))
        return out

    def _start_state(self, t_lo: float) -> _Posterior | None:
        before = [p for p in self.posteriors if p.t <= t_lo + 1e-12]
        return before[-1] if before else None

    def _estimate(self, ctx: Any, d: Detection, t_next: float, say) -> Any:
        from cistrack.least_squares.impulse_fit import burn_evidence, fit_impulse
        from cistrack.least_squares.differential_correction import fit_orbit

        lo = float(d.t_burn_bounds[0]) if np.isfinite(d.t_burn_bounds[0]) else float(d.t)
        start = self._start_state(lo)
        if start is None:
            return None
        ms = ctx.measurements
        t = np.asarray(ms.times, dtype=float)
        keep = (t >= start.t - units.days_to_tu(PRE_DAYS)) & (t <= min(d.t + units.days_to_tu(POST_DAYS), t_next))
        arc = ms.subset(keep)
        after = t[keep & (t > start.t)]
        if after.size < 2 or np.sum(keep & (t <= start.t)) < 3:
            return None
        first = float(after[0])
        cands = start.t + (np.arange(CANDIDATES) + 0.5) / CANDIDATES * (first - start.t)
        opts = FitOptions(area_to_mass="off")
        try:
            ballistic = fit_orbit(ctx.dynamics, ctx.sensor, arc, start.mean, start.t, options=opts)
            burn = fit_impulse(ctx.dynamics, ctx.sensor, arc, ballistic.state, start.t, cands, options=opts)
        except (FitError, PropagationError, np.linalg.LinAlgError) as exc:
            say(f"maneuver at {units.tu_to_days(d.t):.3f} d: no delta-v estimate ({exc})")
            return None
        return burn, burn_evidence(ballistic, burn)


def _record(d: Detection, fit: Any) -> dict[str, Any]:
    """One ``summary.maneuvers`` entry: ``t_days`` (the detection), ``t_burn_days`` (the burn time
    estimated by least squares, else the detector's, else NaN), ``t_burn_window_days``,
    ``delta_v_ms`` and ``delta_v_sigma_ms`` (magnitude, m/s; NaN without an estimate),
    ``delta_v_vector_ms`` (synodic components), ``confirmed`` (the least squares' test), the
    detector's name, statistic and threshold."""
    lo, hi = d.t_burn_bounds
    rec: dict[str, Any] = {"t_days": float(units.tu_to_days(d.t)), "detector": d.detector,
                           "statistic": float(d.statistic), "threshold": float(d.threshold),
                           "t_burn_window_days": [float(units.tu_to_days(lo)), float(units.tu_to_days(hi))],
                           "t_burn_days": float(units.tu_to_days(d.t_burn)) if d.t_burn is not None else float("nan"),
                           "delta_v_ms": float("nan"), "delta_v_sigma_ms": float("nan"),
                           "delta_v_vector_ms": [float("nan")] * 3, "confirmed": False}
    if fit is not None:
        burn, ev = fit
        b = burn.searched
        rec.update({"t_burn_days": float(units.tu_to_days(b.t)), "delta_v_ms": b.magnitude_ms,
                    "delta_v_sigma_ms": b.magnitude_sigma_ms,
                    "delta_v_vector_ms": [float(v) for v in b.delta_v_ms], "confirmed": bool(ev.accepted),
                    "cost_drop": float(ev.cost_drop)})
    return {k: _json(v) for k, v in rec.items()}


def _json(v: Any) -> Any:
    """NaN as None (JSON has no NaN), in lists too."""
    if isinstance(v, list):
        return [_json(x) for x in v]
    return None if isinstance(v, float) and not np.isfinite(v) else v


class ManeuverMetric(StepMetric):
    """Metric stage ``maneuvers``: at each update's posterior, ``maneuver_statistic`` (the
    detector's statistic after it) and ``maneuver_detected`` (1.0 when it raised a detection)."""

    name = "maneuvers"

    def __init__(self, watch: ManeuverWatch) -> None:
        self.watch = watch

    def start(self, run: Any) -> None:
        self.watch.start()

    def compute(self, run: Any, step: Any, event: str) -> dict[str, float]:
        if event != "updated" or step.kind != "update":
            return {}
        return {"maneuver_statistic": float(self.watch.statistic), "maneuver_detected": float(self.watch.fired)}
