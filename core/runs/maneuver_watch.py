"""A run's maneuver watch: the detector at every update, the response, the delta-v estimate.

At each update step the run hands the watch the prior and the measurements before the filter takes
them (:meth:`ManeuverWatch.before_update`). The scenario's detector (``[maneuvers] detector``)
judges them; on a detection the response (``[maneuvers] response``, default none) may hand back a
widened cloud, from which the filter starts again before it takes the measurements (a response
with ``needs_history`` also gets a :class:`~cistrack.interfaces.maneuvers.ResponseHistory`:
:meth:`ManeuverWatch.history`). The watch keeps
each update's posterior mean (:meth:`after_update`), so that at the end of the run
(:meth:`records`) the detections are grouped in episodes (:func:`episodes`: a filter that does not
recover from a burn raises detection after detection) and each episode's burn is estimated by least
squares over the measurements from :data:`PRE_DAYS` before its first detection's suspect interval
(not before the previous episode's, and from a settled posterior: :data:`SETTLED_KM`) to
:data:`POST_DAYS` after the detection, started from the filter's posterior at the arc's start, which is also the state's prior there (what the filter learned before the arc: without
it a few days of one site's angles absorb a small burn into another ballistic orbit): a ballistic
fit, then the burn search of :mod:`cistrack.least_squares.burn_search` (the gaps screened, the burn time's
profile, the delta-v as solve-for parameters, tested against the ballistic fit). The latest burn
kept before the detection is its estimate (``confirmed`` when it passes :func:`_doubt`'s consistency
checks, else unconfirmed with the reason, ``unconfirmed_reason``, and its numbers); a detection for
which the search keeps none is reported unconfirmed, without a delta-v.

The metric stage ``maneuvers`` (:class:`ManeuverMetric`) writes each update's test statistic
(``maneuver_statistic``) and whether it raised a detection (``maneuver_detected``).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import PropagationError
from cistrack.interfaces.maneuvers import (Detection, ManeuverDetector, ManeuverResponse, ResponseHistory,
                                           SettledPosterior)
from cistrack.interfaces.component import component_name
from cistrack.interfaces.metric import StepMetric
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.options import FitOptions
from cistrack.runs.maneuver_contract import checked_observation, checked_response_cloud, plugin_call

__all__ = ["ManeuverWatch", "ManeuverMetric", "PRE_DAYS", "POST_DAYS", "EPISODE_DAYS", "SETTLED_KM", "episodes"]

PRE_DAYS = 1.0
"""The burn's arc starts this many days before the detection's suspect interval (about one pass
earlier: a small burn is often detected a pass late, its interval starting after the burn)."""
SETTLED_KM = 1000.0
"""The arc starts from a posterior whose largest position sigma is below this (km): one the filter
has settled, not the IOD's cloud."""
POST_DAYS = 3.0
"""Days of measurements after the detection in the delta-v estimate (fewer when the next
episode's suspect interval starts sooner). A burn in the gap before a pass is often detected at
that pass's first update; two days after it then hold only two passes, and the burn's sigma is
several times what three give (``example-1-burn`` seed 1: 0.53 against 0.093 m/s)."""
EPISODE_DAYS = 1.5
"""A detection this close (days) after the one before it belongs to the same maneuver (about one
pass and the gap after it in the examples)."""


@dataclass
class _Posterior:
    t: float
    mean: np.ndarray
    covariance: np.ndarray


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
    names: tuple[str, str] = ("", "")
    """The detector and the response as messages name them (kind, name and distribution, e.g.
    ``maneuver-detector 'mine' (hplug 0.1)``); default: kind and name."""
    first_t: float | None = None

    def start(self) -> None:
        self.detector.reset()
        self.detections.clear()
        self.posteriors.clear()
        self.first_t = None

    def before_update(self, ctx: Any, t: float, prior: Any, measurements: tuple, step: int | None = None) -> Any:
        """The detector's verdict on ``measurements`` at ``t`` (TU) under ``prior`` (update ``step``);
        returns the response's cloud (the filter starts again from it) or None. A detector or
        response that raises or breaks its contract is a PluginError naming it
        (:mod:`cistrack.runs.maneuver_contract`)."""
        detector_who, response_who = self._who()
        where = f"at {'' if step is None else f'step {step}, '}t = {float(units.tu_to_days(t)):.3f} d"
        self.first_t = float(t) if self.first_t is None else self.first_t
        out = plugin_call(detector_who, where, self.detector.observe, t, prior, measurements, ctx.sensor)
        self.statistic, detection = checked_observation(out, t, self.first_t, detector_who, where)
        self.fired = detection is not None
        if detection is None:
            return None
        if not detection.detector:
            detection.detector = self.detector.registry_name or type(self.detector).__name__
        before = self.detections[-1].t if self.detections else -np.inf
        self.detections.append(detection)
        if self.response is None:
            return None
        extra = {"history": self.history(ctx, detection, before)} if getattr(self.response, "needs_history", False) else {}
        cloud = plugin_call(response_who, where, self.response.respond, detection, prior, ctx.dynamics, self.rng, **extra)
        return checked_response_cloud(cloud, detection, response_who)

    def _who(self) -> tuple[str, str]:
        """(detector, response) as messages name them: :attr:`names`, else kind and name."""
        return (self.names[0] or f"maneuver-detector '{component_name(self.detector)}'",
                self.names[1] or f"maneuver-response '{component_name(self.response)}'")

    def history(self, ctx: Any, d: Detection, before: float = -np.inf) -> ResponseHistory:
        """What the run saw before the detection ``d``: the measurements before ``d.t`` (TU), the
        sensor, and the settled posterior the burn's arc starts from (as :meth:`_estimate`'s:
        :data:`PRE_DAYS` before the suspect interval, not before ``before``, the previous detection)."""
        lo = float(d.t_burn_bounds[0]) if np.isfinite(d.t_burn_bounds[0]) else float(d.t)
        start = self._start_state(max(lo - float(units.days_to_tu(PRE_DAYS)), before), lo)
        posterior = None if start is None else SettledPosterior(start.t, start.mean.copy(), start.covariance.copy())
        t = np.asarray(ctx.measurements.times, dtype=float)
        say = self.say or (lambda m: None)
        return ResponseHistory(ctx.measurements.subset(t < float(d.t)), ctx.sensor, posterior, say)

    def after_update(self, t: float, belief: Any) -> None:
        """Keep the posterior mean (6,) and covariance (6, 6) at ``t`` (TU)."""
        mean = np.asarray(belief.mixture.mean, dtype=float)
        cov = np.asarray(belief.mixture.covariance, dtype=float)
        if np.all(np.isfinite(mean)) and np.all(np.isfinite(cov)):
            self.posteriors.append(_Posterior(float(t), mean.copy(), cov.copy()))

    def records(self, ctx: Any) -> list[dict[str, Any]]:
        """``summary.maneuvers``: one entry per episode of detections (:func:`episodes`), with the
        burn estimated around its first detection (:func:`_record`)."""
        say = self.say or (lambda m: None)
        groups = episodes(self.detections)
        out = []
        for k, group in enumerate(groups):
            before = groups[k - 1][0].t if k > 0 else -np.inf
            after = float(groups[k + 1][0].t_burn_bounds[0]) if k + 1 < len(groups) else np.inf
            burn = self._estimate(ctx, group[0], (before, after), say) if self.estimate else None
            out.append(_record(group, burn, estimated=self.estimate))
        return out

    def _start_state(self, target: float, latest: float) -> _Posterior | None:
        """The posterior the burn's arc starts from: the latest settled one (position sigma below
        :data:`SETTLED_KM`) at or before ``target`` (TU), else the earliest settled one before
        ``latest``; None when there is none."""
        settled = [p for p in self.posteriors
                   if np.sqrt(np.max(np.diag(p.covariance)[:3])) * units.LU_KM < SETTLED_KM]
        before = [p for p in settled if p.t <= target + 1e-12]
        if before:
            return before[-1]
        early = [p for p in settled if p.t < latest]
        return early[0] if early else None

    def _estimate(self, ctx: Any, d: Detection, between: tuple[float, float], say) -> Any:
        """The burn nearest before the detection ``d`` found in the arc around it (module
        docstring) with why it is not confirmed (:class:`_Estimate`, :func:`_doubt`,
        :func:`_start_doubt`), or None; ``between``: the previous episode's detection and the next
        episode's suspect interval start (TU), which the arc stays within."""
        lo = float(d.t_burn_bounds[0]) if np.isfinite(d.t_burn_bounds[0]) else float(d.t)
        start = self._start_state(max(lo - float(units.days_to_tu(PRE_DAYS)), between[0]), lo)
        found = None if start is None else self._search(ctx, d, between, start, say)
        if found is None:
            return None
        found, burns, ballistic, arc = found
        rival = _rival(arc, ballistic, found, burns[-1], d.t)
        return _Estimate(burns[-1], _doubt(found, burns, d.t, ballistic, rival) or _start_doubt(burns[-1], start.t))

    def _search(self, ctx: Any, d: Detection, between: tuple[float, float], start: Any, say) -> Any:
        """(the search, its burns before ``d``, the ballistic fit, the :class:`BurnArc`) of the arc
        from the settled posterior ``start`` to :data:`POST_DAYS` after ``d``; None when the arc is
        too short, the fits fail or the search keeps no burn before ``d``."""
        from cistrack.least_squares.burn_search import search_maneuvers
        from cistrack.least_squares.differential_correction import fit_orbit
        from cistrack.least_squares.impulse_fit import BurnArc

        t = np.asarray(ctx.measurements.times, dtype=float)
        end = d.t + float(units.days_to_tu(POST_DAYS))
        keep = (t >= start.t) & (t <= end) & ((t < between[1]) | (t <= d.t))
        if np.sum(keep & (t > d.t - 1e-12)) < 2 or np.sum(keep & (t < d.t)) < 3:
            return None
        arc = ctx.measurements.subset(keep)
        opts = FitOptions(area_to_mass="off")
        prior = (start.mean, start.covariance)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UnobservableWarning)  # a short arc: the prior carries it
                ballistic = fit_orbit(ctx.dynamics, ctx.sensor, arc, start.mean, start.t, options=opts, prior=prior)
                found = search_maneuvers(ctx.dynamics, ctx.sensor, arc, ballistic, opts, prior=prior)
        except (FitError, PropagationError, np.linalg.LinAlgError) as exc:
            say(f"maneuver detected at {units.tu_to_days(d.t):.3f} d: no delta-v estimate ({exc})")
            return None
        burns = [b for b in found.burns if b.t <= d.t]
        if not burns:
            return None
        return found, burns, ballistic, BurnArc(ctx.dynamics, ctx.sensor, arc, opts, prior)


AT_START_SECONDS = 60.0
"""A burn estimated this close after the start of its arc (at the first instant the search may put
it) may have happened before the arc: the filter's posterior the arc starts from then already holds
part of it, and the search puts the change at the start. ``example-1-maneuver`` (0.1 m/s
station-keeping burns, often detected passes late), confirmed estimates at their arc's start:
seeds 2700-2729, 11, 9 of them with their time 3-6 sigma from the truth; unseen seeds 3680-3709,
4, 3 of them beyond 3 sigma. Widening the rule to two sigmas of the burn time caught as many
right estimates as wrong ones (such arcs often start a few hours before the true burn), and
starting such an arc a day earlier and searching again moved as many estimates away from the
truth as towards it (3680-3709: 13 of 39 confirmed beyond 3 sigma, 13 of 41 before)."""


def _at_start(burn: Any, start: float) -> bool:
    """Whether ``burn`` lies within :data:`AT_START_SECONDS` after ``start`` (TU)."""
    return burn.t - start <= float(units.seconds_to_tu(AT_START_SECONDS))


def _start_doubt(burn: Any, start: float) -> str:
    """Why a burn at its arc's start (:func:`_at_start`) is not confirmed ("" when it is not there)."""
    if not _at_start(burn, start):
        return ""
    return (f"its burn time {units.tu_to_days(burn.t):.3f} d is the start of its arc: the burn may have happened "
            "before the arc, whose starting belief (the filter's) then holds part of it")


@dataclass(frozen=True)
class _Estimate:
    """The burn the search kept for an episode, and why it is not confirmed ("" when it is)."""

    burn: Any
    doubt: str = ""


GOODNESS_FALSE_ALARM = 1e-4
"""The false-alarm level of the fit-with-the-burn's goodness-of-fit test (:func:`_doubt`)."""


def _rival(arc: Any, ballistic: Any, found: Any, burn: Any, t_detect: float) -> Any:
    """:func:`cistrack.least_squares.burn_search.rival_time` of ``burn``, None when it fails."""
    from cistrack.least_squares.burn_search import rival_time

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UnobservableWarning)
            return rival_time(arc, ballistic, found, burn, t_detect)
    except (FitError, PropagationError, np.linalg.LinAlgError):
        return None


def _doubt(found: Any, before: list, t_detect: float, ballistic: Any = None, rival: Any = None) -> str:
    """Why the latest of the burns ``before`` the detection (TU ``t_detect``) that the search
    ``found`` kept is not a confirmed estimate, in words ("" when it is):

    - its time's uncertainty was not measured (t_sigma 0 is never a measured value);
    - its time lies outside the gap the search placed it in, or after the detection;
    - the search kept more than one burn before the detection: the change the detector saw is split
      over several burns (a large burn whose linearised profile missed its time, ``example-1-burn``
      seed 3 at 100 m/s: 17.6 m/s at 3.116 d and 82 m/s at 3.840 d for one 100 m/s burn at 3.620 d),
      and the latest's delta-v is not the maneuver's;
    - the fit with every burn does not fit the measurements: its capped cost (each observation's
      chi-square capped at the rejection threshold, plus the prior's term) exceeds the chi-square
      quantile at :data:`GOODNESS_FALSE_ALARM` of its degrees of freedom (measurement components
      minus 3 per burn and the solve-for parameters; the prior's 6 rows balance the state's 6);
    - the measurements alone do not call for the burns (:func:`_prior_only`, given the ``ballistic``
      fit the search started from);
    - another burn time the measurements allow, the ``rival``
      (:class:`~cistrack.least_squares.burn_search.RivalTime`), needs a delta-v outside the
      estimate's covariance (:func:`_unstable`).
    """
    return (_time_doubt(found, before, t_detect) or _goodness_doubt(found) or _prior_only(found, ballistic)
            or _unstable(rival))


def _time_doubt(found: Any, before: list, t_detect: float) -> str:
    """:func:`_doubt`'s checks of the burn's time: measured, inside its gap, before the detection,
    the only burn before it."""
    burn = before[-1]
    days = units.tu_to_days
    if burn.dv_dt is None or not burn.t_sigma > 0:
        why = next((n for n in found.notes if "uncertainty was not measured" in n), "")
        return "its burn time's uncertainty could not be measured" + (f" ({why})" if why else "")
    k = next((j for j, b in enumerate(found.burns) if b is burn), None)
    if k is not None and k < len(found.windows):
        lo, hi = found.windows[k]
        if not lo <= burn.t <= hi:
            return (f"its burn time {days(burn.t):.3f} d lies outside the gap {days(lo):.3f}-{days(hi):.3f} d "
                    "the search placed it in")
    if burn.t > t_detect:
        return f"its burn time {days(burn.t):.3f} d is after the detection"
    if len(before) > 1:
        at = ", ".join(f"{b.magnitude_ms:.3g} m/s at {days(b.t):.3f} d" for b in before)
        return f"the search split the change over {len(before)} burns before the detection ({at})"
    return ""


def _goodness_doubt(found: Any) -> str:
    """:func:`_doubt`'s goodness-of-fit test of the fit with every burn."""
    from cistrack.least_squares.chi_square import chi2_ppf
    from cistrack.least_squares.impulse_fit import capped_cost

    fit = found.result
    comps = int(np.sum(np.isfinite(np.asarray(fit.residuals.normalised, dtype=float))))
    dof = comps - len(fit.parameter_names) - (0 if found.prior is not None else 6)
    cost = capped_cost(fit, found.prior)
    if dof > 0:
        limit = chi2_ppf(1.0 - GOODNESS_FALSE_ALARM, dof)
        if cost > limit:
            return (f"the fit with the burn does not fit the measurements (cost {cost:.1f} > {limit:.1f}, "
                    f"the chi-square bound of {dof} degrees of freedom at {GOODNESS_FALSE_ALARM:g})")
    return ""


def _prior_only(found: Any, ballistic: Any) -> str:
    """Why the burns' evidence is the prior's rather than the measurements' ("" when it is not).

    With a prior on the state at the arc's start, the search's test counts the prior's term in
    both fits' costs. When the ballistic fit already fits the measurements and the burns lower
    mostly the prior's term, what the arc shows is that its measurements and its prior disagree:
    a burn before the arc's start (the filter's posterior there taken after it, ``example-1-burn``
    seed 2 with 2 m/s at 2.0 d: the arc starts at 2.094 d and a burn of 9.8 m/s at 2.33 d,
    4 sigma off, lowered the prior's term from 24.4 to 2.4 and the measurements' chi-square from
    33.1 to 29.7), or a prior that is off, explains that as well as a burn inside the arc. So the
    measurements' own part of the cost (each observation's chi-square capped at the rejection
    threshold) must drop by more than the search's threshold: the chi-square quantile of 4
    degrees of freedom per burn at :data:`cistrack.least_squares.burn_search.FALSE_ALARM`."""
    from cistrack.least_squares.burn_search import FALSE_ALARM
    from cistrack.least_squares.chi_square import chi2_ppf
    from cistrack.least_squares.impulse_fit import capped_cost

    if ballistic is None or found.prior is None or not found.burns:
        return ""
    drop = capped_cost(ballistic) - capped_cost(found.result)
    limit = chi2_ppf(1.0 - FALSE_ALARM, 4 * len(found.burns))
    if drop > limit:
        return ""
    before, after = (capped_cost(f, found.prior) - capped_cost(f) for f in (ballistic, found.result))
    return (f"the measurements alone do not call for the burn: it lowers their chi-square by {drop:.1f} "
            f"(a burn needs > {limit:.1f}) and the prior's term from {before:.1f} to {after:.1f}; a burn before "
            f"the arc's start at {units.tu_to_days(ballistic.epoch):.3f} d, or a prior that is off, explains "
            "the arc as well")


def _unstable(rival: Any) -> str:
    """Why the estimate's time and delta-v are not determined ("" when they are, ``rival`` None):
    another burn time fits about as well with a delta-v the two estimates' covariances do not cover
    (:func:`cistrack.least_squares.burn_search.rival_time`)."""
    from cistrack.least_squares.burn_search import RIVAL_COST, RIVAL_FALSE_ALARM
    from cistrack.least_squares.chi_square import chi2_ppf

    if rival is None:
        return ""
    dv = ", ".join(f"{v:+.3g}" for v in rival.delta_v_ms)
    return (f"its burn time and delta-v are not determined: a burn at {units.tu_to_days(rival.t):.3f} d fits "
            f"about as well (cost {rival.cost_delta:+.1f}, within {RIVAL_COST:g}) with a delta-v of ({dv}) m/s, "
            f"chi-square {rival.chi2:.1f} from the estimate's in their two covariances "
            f"(> {chi2_ppf(1.0 - RIVAL_FALSE_ALARM, 3):.1f}, 3 dof at {RIVAL_FALSE_ALARM:g})")


def episodes(detections: list[Detection]) -> list[list[Detection]]:
    """The detections in episodes: a detection within :data:`EPISODE_DAYS` of the one before it
    continues that one's episode (a filter that does not recover from a burn keeps raising
    detections of it); each episode is one maneuver reported."""
    out: list[list[Detection]] = []
    for d in detections:
        if out and d.t - out[-1][-1].t <= float(units.days_to_tu(EPISODE_DAYS)):
            out[-1].append(d)
        else:
            out.append([d])
    return out


def _record(group: list[Detection], estimate: Any, estimated: bool = True) -> dict[str, Any]:
    """One ``summary.maneuvers`` entry for an episode of detections (its first ``d``):
    ``t_days`` (the first detection), ``detections`` (how many in the episode), ``t_burn_days`` (the burn time
    estimated by least squares, else the detector's, else NaN), ``t_burn_window_days``,
    ``delta_v_ms`` and ``delta_v_sigma_ms`` (magnitude, m/s; NaN without an estimate),
    ``delta_v_vector_ms`` (synodic components) and, with an estimate, its ``delta_v_covariance_ms2``
    ((3, 3), (m/s)^2, the burn time's uncertainty mapped in), ``confirmed`` (the least squares' test and the
    estimate's consistency, :func:`_doubt`; None when ``estimated`` is False: ``[maneuvers]
    estimate = false`` ran none), ``unconfirmed_reason`` (only when an estimate was made but fails
    that consistency: why; its numbers are still given), the detector's name, statistic and
    threshold."""
    d = group[0]
    lo, hi = d.t_burn_bounds
    rec: dict[str, Any] = {"t_days": float(units.tu_to_days(d.t)), "detector": d.detector, "detections": len(group),
                           "statistic": float(d.statistic), "threshold": float(d.threshold),
                           "t_burn_window_days": [float(units.tu_to_days(lo)), float(units.tu_to_days(hi))],
                           "t_burn_days": float(units.tu_to_days(d.t_burn)) if d.t_burn is not None else float("nan"),
                           "delta_v_ms": float("nan"), "delta_v_sigma_ms": float("nan"),
                           "delta_v_vector_ms": [float("nan")] * 3, "confirmed": False if estimated else None}
    if estimate is not None:
        burn = estimate.burn
        t_sigma = float(units.tu_to_days(burn.t_sigma)) if burn.t_sigma > 0 else float("nan")  # never a measured 0
        rec.update({"t_burn_days": float(units.tu_to_days(burn.t)), "t_burn_sigma_days": t_sigma,
                    "delta_v_ms": burn.magnitude_ms, "delta_v_sigma_ms": burn.magnitude_sigma_ms,
                    "delta_v_vector_ms": [float(v) for v in burn.delta_v_ms],
                    "delta_v_covariance_ms2": [[float(x) for x in row] for row in np.asarray(burn.covariance_ms2)],
                    "confirmed": not estimate.doubt})
        if estimate.doubt:
            rec["unconfirmed_reason"] = estimate.doubt
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
