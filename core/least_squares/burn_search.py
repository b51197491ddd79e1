"""Burns found in an arc of observations: the search that ``cistrack fit`` and a run's maneuver watch share.

A ballistic fit of an object that maneuvered shows it in one of three ways: it rejects a
contiguous block of observations that reaches an end of the arc (those on one side of the burn), its residuals are far larger
than the noise (weighted RMS), or it does not converge. :func:`suspicion` names which. Then
:func:`search_maneuvers` looks for burns in the gaps between the observations (a burn between
nights, or between tracklets of one night):

1. every gap longer than :data:`MIN_GAP_HOURS` is a candidate; a linearised screen about the
   current fit (:func:`cistrack.least_squares.impulse_fit.screen_burn_times`) ranks them;
2. in the best :data:`GAPS_TRIED` gaps the screen's profile over the gap gives the burn time and its
   uncertainty (:func:`cistrack.least_squares.impulse_fit.burn_time_profile`: measured on a 0.3 m/s
   burn, the linearised profile follows the full fits' to a few per cent), and the arc is fitted in
   full with the burn there and its delta-v as solve-for parameters
   (:func:`cistrack.least_squares.impulse_fit.fit_impulse`; from the current fit with every
   observation in the first pass and with its rejections left out, the cheaper kept:
   :func:`_gap_starts`); the screen is made again about the
   best of those fits' orbits, and a gap it ranks higher is fitted again from there and kept when
   it fits clearly better (:func:`_next_burn`);
3. the best burn is kept when it passes the test against the fit without it
   (:func:`cistrack.least_squares.impulse_fit.burn_evidence`, false alarm :data:`FALSE_ALARM`);
   then the search goes on for another burn (at most :data:`MAX_BURNS`), all delta-v refitted jointly.

Searching ``again`` after a first search, each step also fits the burn from where the orbits of a
gap's two sides, each fitted alone, meet (:mod:`cistrack.least_squares.split_start`): ``cistrack
fit`` searches so when the search above leaves the arc unexplained, reusing its screened fits.

``cistrack fit`` records each burn kept in ``fit.json``'s ``maneuvers``
(:mod:`cistrack.fitting.maneuver_search`); a run's maneuver watch in ``summary.maneuvers``
(:mod:`cistrack.runs.maneuver_watch`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.errors import PropagationError
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.maneuvers import Impulse
from cistrack.interfaces.sensor import Sensor
from cistrack.least_squares.chi_square import chi2_ppf
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.impulse_fit import (MS_PER_VU, BurnArc, BurnEstimate, ImpulseFit, burn_evidence,
                                                burn_time_profile, capped_cost, fit_impulse, fit_impulses, refit_moved,
                                                rejected_of, screen_burn_times, with_time_uncertainty)
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.result import FitResult
from cistrack.least_squares.split_start import SPLIT_GAPS, split_candidates, split_fit
from cistrack.model.measurement import MeasurementSet
from cistrack.least_squares.trajectory import arc_states
from cistrack.propagation.impulses import ImpulsiveDynamics

__all__ = ["suspicion", "screen_suspicion", "end_night_bias", "end_night_rejected", "burn_fit_options", "BURN_ITERATIONS", "END_BIAS_CHI2", "search_maneuvers", "ManeuverSearch", "burn_key", "flown", "rival_time", "RivalTime", "MIN_GAP_HOURS",
           "MAX_BURNS", "FALSE_ALARM", "GAPS_TRIED", "BLOCK_SHARE", "MAX_RMS", "MAX_BURN_MS", "RIVAL_COST", "ALLOWED_COST",
           "RIVAL_FALSE_ALARM", "RIVAL_SCREEN_SLACK", "times_allowed", "any_size"]

MIN_GAP_HOURS = 0.2
"""Gaps between observations at least this long (12 minutes) are candidate burn intervals: between
nights, and between the tracklets or exposures of one night."""
DENSE_WINDOW_HOURS = 1.0
"""A stretch of observations each closer than :data:`MIN_GAP_HOURS` to the next that spans at least
this long (a pass of a dense follow-up campaign; a survey's tracklet spans 10-30 minutes) is a
candidate burn interval as a whole (:func:`_windows`): a burn among its observations had had only
the gaps around it to be placed in (a 0.71 m/s burn of a three-site campaign, observed every few
minutes, placed an hour early, eight of its time sigmas)."""
MAX_BURNS = 3
"""At most this many burns are searched for in one arc."""
FALSE_ALARM = 1e-4
"""The false-alarm probability of each burn's test against the fit without it."""
GAPS_TRIED = 2
"""Gaps fitted in full per burn, the best of the linearised screen."""
GAP_POINTS = 6
"""Burn times per gap in the linearised screen that ranks the gaps."""
BLOCK_SHARE = 0.05
"""A contiguous block of rejected observations this large a share of the arc (and at least
:data:`BLOCK_MIN` observations) makes a fit suspect."""
BLOCK_MIN = 4
BURN_ITERATIONS = 100
"""Levenberg-Marquardt iterations per pass, at least, of every fit with a burn that ``cistrack
fit`` makes (:func:`burn_fit_options`; the ballistic fit's default is 30). A survey fit with the
right 1 m/s burn (heo-s198: cost 41,384 below the ballistic fit's, weighted RMS 0.94) stopped at
30 iterations not converged along the ill-conditioned valley of state and delta-v, and the burn
was not kept. A fit that converges within 30 is the same fit."""

MAX_BURN_MS = 1000.0
"""The largest burn the search keeps, m/s (a lunar orbit insertion's size; a cislunar object moves
at about 1 km/s, and the escape speed from the Earth at the Moon's distance is 1.4 km/s): a larger
one fitted between observations of a cislunar object explains outliers or another object, not a
maneuver. A burn whose size's sigma exceeds it is of any size too: the observations bound none."""
MAX_RMS = 1.5
"""A fit whose weighted RMS exceeds this is suspect (1 when the noise is as stated)."""
RIVAL_COST = 4.0
"""A burn time whose fit costs at most this much more than the estimate's is one the measurements
allow (:func:`rival_time`): the two-sigma interval of the time's profile (1 dof)."""
ALLOWED_COST = 9.0
"""A burn time whose full fit costs at most this much more than the estimate's is one the arc
allows (:func:`times_allowed`): the profile's three-sigma interval (1 dof). One costing c more
lies max(2, sqrt(c)) of the widened time sigmas away. An unseen survey set's 0.5 m/s burn lay in a
gap whose full fit cost 4.3 more than the one reported (time z -13.4, the fit called clean)."""
RIVAL_FALSE_ALARM = 1e-4
"""The level of :func:`rival_time`'s test that another burn time's delta-v lies outside the
estimate's covariance."""
RIVAL_SCREEN_SLACK = 3.0
""":func:`rival_time` fits in full the candidate times whose linearised screen cost lies within
:data:`RIVAL_COST` plus this of the screen's best (the screen about the ballistic fit is within a
few units of the full fits' costs near a 1 m/s burn)."""


def burn_fit_options(options: FitOptions) -> FitOptions:
    """``options`` with at least :data:`BURN_ITERATIONS` iterations per pass."""
    return replace(options, max_iterations=max(options.max_iterations, BURN_ITERATIONS))


def _end_block(rejected: np.ndarray) -> int:
    """The longer run of rejections that starts the arc or ends it (time order)."""
    def lead(r: np.ndarray) -> int:
        kept = np.flatnonzero(~r)
        return int(kept[0]) if kept.size else int(r.size)

    return max(lead(rejected), lead(rejected[::-1]))


def suspicion(result: FitResult) -> str:
    """Why the ballistic ``result`` looks like an object that maneuvered, in words ("" when it
    does not): a contiguous block of rejections at the start or the end of the arc, a first or
    last night rejected whole (:func:`end_night_rejected`) or off the fit together
    (:func:`end_night_bias`), a large RMS, or no convergence.

    The block must reach an end of the arc: after a burn every later observation is off the
    ballistic orbit, so a fit that follows one side rejects the other side to the arc's end. A
    block between accepted observations (one mis-identified tracklet, one site's wrong position)
    is bad data, not a maneuver: it is rejected and the fit stays clean."""
    order = np.argsort(result.residuals.times, kind="stable")
    rejected = np.asarray(result.residuals.rejected, dtype=bool)[order]
    block = _end_block(rejected)
    if block >= max(BLOCK_MIN, BLOCK_SHARE * rejected.size):
        return (f"it rejects a contiguous block of {block} of {rejected.size} observations "
                f"({100.0 * block / rejected.size:.0f} %)")
    bias = end_night_rejected(result) or end_night_bias(result)
    if bias:
        return bias
    if result.rms > MAX_RMS:
        return f"its weighted RMS is {result.rms:.2f} (1 when the residuals are noise)"
    if not result.converged:
        return "it did not converge"
    return ""


def screen_suspicion(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, result: FitResult,
                     options: FitOptions) -> str:
    """Why a ballistic ``result`` that :func:`suspicion` passes still looks like an object that
    maneuvered, in words ("" when it does not): the linearised screen of a burn in each gap
    (:func:`_screen_gaps`, about ``result``, made with ``dynamics``) lowers its capped cost by more
    than a burn's test needs (chi-square of 4 dof at :data:`FALSE_ALARM`). A ballistic orbit can
    follow both sides of a long gap within the noise: an unseen survey set of an Earth orbit with a
    0.3 m/s burn in a six-day gap fitted with weighted RMS 1.16, nothing rejected but the injected
    outliers, its truth at Mahalanobis^2 4.6e6; a burn in that gap lowers the cost by 72 (23.5
    needed), while on 24 maneuver-free sets the largest drop was 12."""
    gaps = _windows(ms.times, [])
    if not gaps:
        return ""
    opts = replace(options, area_to_mass="solve" if result.parameter_names else "off")
    try:
        drops = capped_cost(result, None) - _screen_gaps(BurnArc(dynamics, sensor, ms, opts, None), result, gaps)
    except (PropagationError, FitError, np.linalg.LinAlgError):
        return ""
    k, limit = int(np.argmax(drops)), chi2_ppf(1.0 - FALSE_ALARM, 4)
    if not drops[k] > limit:
        return ""
    return (f"a burn in the gap {_utc_days(gaps[k][0]):.2f}-{_utc_days(gaps[k][1]):.2f} d lowers its cost by "
            f"{drops[k]:.0f} in a linearised screen (a burn's test needs {limit:.1f})")


END_BIAS_CHI2 = 18.42
"""The chi-square (2 degrees of freedom, false alarm 1e-4) beyond which the mean normalised
residual of the first or the last night of an arc is a bias, not noise (:func:`end_night_bias`)."""
END_NIGHT_GAP_HOURS = 6.0
"""Observations closer than this belong to one night (:func:`end_night_bias`)."""


def _end_nights(times: np.ndarray) -> list[tuple[str, slice]]:
    """The first and the last night of the time-sorted ``times`` (TU) as slices, observations closer
    than :data:`END_NIGHT_GAP_HOURS` making one night; none when the arc is one night."""
    cuts = np.flatnonzero(np.diff(times) >= units.hours_to_tu(END_NIGHT_GAP_HOURS)) + 1
    if cuts.size == 0:
        return []
    return [("first", slice(0, int(cuts[0]))), ("last", slice(int(cuts[-1]), times.size))]


def end_night_rejected(result: FitResult) -> str:
    """Why ``result`` rejects the whole first or last night of its arc, in words ("" when it does
    not): every observation of that night, at least two. Independent outliers take a whole night
    only by chance; a burn before the last night (or after the first) takes it together. Too short a
    night for :data:`BLOCK_MIN` or :func:`end_night_bias` had hidden that: a survey fit rejected
    its last tracklet, two exposures after a 10 m/s burn, and reported "converged" with its state
    propagated two days past the last observation it used, the truth 10^9 in Mahalanobis^2 away."""
    order = np.argsort(result.residuals.times, kind="stable")
    t = np.asarray(result.residuals.times, dtype=float)[order]
    rejected = np.asarray(result.residuals.rejected, dtype=bool)[order]
    for name, part in _end_nights(t):
        if rejected[part].size >= 2 and rejected[part].all():
            return f"it rejects all {rejected[part].size} observations of its {name} night"
    return ""


def end_night_bias(result: FitResult) -> str:
    """Why the first or the last night of ``result``'s arc sits off the fit together, in words (""
    when neither does): the median normalised residual of its observations (used or rejected, at
    least 3; the median, so that a gross outlier among them does not count), n |median|^2 / (pi/2)
    (the median's variance in noise) beyond :data:`END_BIAS_CHI2`. After a burn the observations
    that follow are off the ballistic orbit together; a fit of sparse survey tracklets can follow
    both sides but for the last night, rejecting some of its exposures and keeping others, so that
    no contiguous block shows it (a 0.5 m/s burn the night before an arc's last tracklet: three of
    its four exposures rejected, all four 2-3.4 arcsec off in Dec, 6 sigma)."""
    t = np.asarray(result.residuals.times, dtype=float)
    z = np.asarray(result.residuals.normalised, dtype=float)
    order = np.argsort(t, kind="stable")
    t, z = t[order], z[order]
    for name, part in _end_nights(t):
        zk = z[part]
        zk = zk[np.all(np.isfinite(zk), axis=1)]
        if len(zk) >= 3:
            stat = float(len(zk) * np.sum(np.median(zk, axis=0) ** 2) / (0.5 * np.pi))
            if stat > END_BIAS_CHI2:
                return (f"the {len(zk)} observations of its {name} night sit off it together: their median residual "
                        f"is {np.sqrt(stat):.1f} sigma")
    return ""


@dataclass
class ManeuverSearch:
    """What :func:`search_maneuvers` found.

    Attributes
    ----------
    result : FitResult             the fit with every burn kept (the ballistic fit when none is)
    dynamics : Dynamics            the model that flies ``result`` (with the burns' impulses)
    burns : list of BurnEstimate   the burns kept, in time order
    windows : list of (float, float)   TU, the gap each burn lies in
    notes : list of str            what the search did, in words
    prior : (mean (6,), covariance (6, 6)) or None   the prior on the state at the fit's epoch
                                   every fit of the search was made with
    screened : dict                the screened step (:func:`_screened_burn`'s result and notes) for
                                   each set of burns found so far (:func:`burn_key`): a second search
                                   of the same ballistic fit given it reuses those fits
    ballistic : FitResult or None  the fit without burns the search began from (the time check
                                   fits trial times from it too: :func:`_from_ballistic`)
    unsized : str                  why the search stopped at a burn that lowers the cost enough but is
                                   of any size (:func:`any_size`), in words ("" when it did not)
    """

    result: FitResult
    dynamics: Dynamics
    burns: list[BurnEstimate] = field(default_factory=list)
    windows: list[tuple[float, float]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    prior: Any = None
    screened: dict = field(default_factory=dict, repr=False)
    ballistic: FitResult | None = field(default=None, repr=False)
    unsized: str = ""


def burn_key(burns: list[BurnEstimate]) -> tuple:
    """The burns' times (TU) and delta-v (m/s) as a hashable key: equal only for the same burns."""
    return tuple((float(b.t), *np.asarray(b.delta_v_ms, dtype=float).tolist()) for b in burns)


def _gaps(times: np.ndarray, done: list[tuple[float, float]]) -> list[tuple[float, float]]:
    t = np.unique(np.asarray(times, dtype=float))
    dt = units.hours_to_tu(MIN_GAP_HOURS)
    return [(float(a), float(b)) for a, b in zip(t[:-1], t[1:]) if b - a >= dt and (float(a), float(b)) not in done]


def _windows(times: np.ndarray, done: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The candidate burn intervals (TU) in time order but those ``done``: every gap of at least
    :data:`MIN_GAP_HOURS` between observations, and every stretch of closer observations spanning
    at least :data:`DENSE_WINDOW_HOURS` (from its first observation to its last)."""
    t = np.unique(np.asarray(times, dtype=float))
    dt, dense = units.hours_to_tu(MIN_GAP_HOURS), units.hours_to_tu(DENSE_WINDOW_HOURS)
    out: list[tuple[float, float]] = []
    start = None
    for a, b in zip(t[:-1].tolist(), t[1:].tolist()):
        if b - a < dt:
            start = a if start is None else start
            continue
        if start is not None and a - start >= dense:
            out.append((start, a))
        start = None
        out.append((a, b))
    if start is not None and t[-1] - start >= dense:
        out.append((start, float(t[-1])))
    return [w for w in out if w not in done]


def flown(dynamics: Dynamics, burns: list[BurnEstimate]) -> Dynamics:
    """``dynamics`` flying the estimated ``burns`` (itself when there are none)."""
    if not burns:
        return dynamics
    return ImpulsiveDynamics(dynamics, [Impulse(b.t, b.delta_v_ms / MS_PER_VU, f"burn {k + 1}")
                                        for k, b in enumerate(burns)])


def _screen_gaps(flown: BurnArc, about: FitResult, gaps: list) -> np.ndarray:
    """The linearised capped cost (G,) of a burn in each gap, about the fit ``about``: the best of
    :data:`GAP_POINTS` times."""
    fr = (np.arange(GAP_POINTS) + 0.5) / GAP_POINTS
    ts = np.array([a + f * (b - a) for a, b in gaps for f in fr])
    costs = screen_burn_times(flown, about, ts)
    return costs.reshape(len(gaps), GAP_POINTS).min(axis=1)


def _next_burn(arc: BurnArc, found: ManeuverSearch,
               split: bool = False) -> tuple[ImpulseFit, tuple[float, float], float] | None:
    """The best fit with one more burn, its gap and its time's one sigma (TU); None when no gap
    gives a fit.

    The gaps are ranked, and the time in a gap chosen, by the linearised screen about the fit
    without the new burn; the best :data:`GAPS_TRIED` are fitted in full. The screen is then made
    again about the best of those fits' orbits with the new burn left out (a trajectory that follows
    the arc on one side of it, where the first screen's, the compromise between both sides, may
    follow neither), and up to :data:`GAPS_TRIED` gaps it ranks above the chosen one are fitted in
    full again from that orbit, at the profile's time and one sigma either side; one replaces the
    choice when its fit costs more than :data:`RIVAL_COST` less (a clear preference, not noise
    between two neighbouring gaps): survey set dro-s90 (seed 90, 0.5 m/s) had its burn placed between two tracklets of a
    night 1.4 days after it, the true four-day gap not among the first screen's two best, a fit
    there costing 32 less.

    With ``split`` the gaps whose two sides determine their orbits alone are fitted in full from
    where those orbits meet too (:mod:`cistrack.least_squares.split_start`), and the best of all
    the fits is kept."""
    gaps = _windows(arc.measurements.times, found.windows)
    if not gaps:
        return None
    best = _screened_once(arc, found, gaps)
    return _better(best, _split_burn(arc, found, gaps)) if split else best


def _screened_once(arc: BurnArc, found: ManeuverSearch,
                   gaps: list[tuple[float, float]]) -> tuple[ImpulseFit, tuple[float, float], float] | None:
    """:func:`_screened_burn`, or its result (and notes) kept in ``found.screened`` for the same
    burns: the second search ``cistrack fit`` makes begins with the same fits as the first."""
    key = burn_key(found.burns)
    if key in found.screened:
        best, notes = found.screened[key]
        found.notes.extend(notes)
        return best
    n = len(found.notes)
    best = _screened_burn(arc, found, gaps)
    found.screened[key] = (best, found.notes[n:])
    return best


def _screened_burn(arc: BurnArc, found: ManeuverSearch,
                   gaps: list[tuple[float, float]]) -> tuple[ImpulseFit, tuple[float, float], float] | None:
    """:func:`_next_burn`'s fits in the gaps the linearised screen ranks best."""
    flown = replace(arc, dynamics=found.dynamics)  # the burns found so far flown
    best = None
    for _ in range(2):
        about = found.result if best is None else replace(found.result, state=best[0].fit.state)
        try:
            ranked = [int(g) for g in np.argsort(_screen_gaps(flown, about, gaps), kind="stable")]
        except PropagationError as exc:  # an orbit about which no gap can be screened (it meets the Moon)
            found.notes.append(f"the gaps could not be screened for another burn ({exc})")
            return best
        if best is not None:  # only gaps the new screen puts above the chosen one
            ranked = ranked[:ranked.index(gaps.index(best[1]))]
        again = best is not None
        for g in ranked[:GAPS_TRIED]:
            best = _better(best, _gap_fit(arc, flown, about, found, gaps[g], spread=again), RIVAL_COST if again else 0.0)
        if best is None:
            return None
    return best


def _split_burn(arc: BurnArc, found: ManeuverSearch,
                gaps: list[tuple[float, float]]) -> tuple[ImpulseFit, tuple[float, float], float] | None:
    """(fit, gap, time sigma) of the best fit started where the orbits of a gap's two sides meet
    (:data:`~cistrack.least_squares.split_start.SPLIT_GAPS` gaps, nearest meeting first); None when
    no gap's sides determine their orbits or no fit can be made. The time's sigma is the linearised
    profile's about the fit's orbit with the new burn left out (a fifth of the gap when that fails)."""
    best = None
    for sp in split_candidates(arc, found.result, found.dynamics, gaps, lambda f: f.rms <= MAX_RMS)[:SPLIT_GAPS]:
        fit = split_fit(arc, found.result, found.dynamics, sp, found.burns)
        if fit is None:
            continue
        try:
            _, t_sigma = burn_time_profile(replace(arc, dynamics=found.dynamics),
                                           replace(found.result, state=fit.fit.state), *sp.gap)
        except (FitError, PropagationError):
            t_sigma = (sp.gap[1] - sp.gap[0]) / 5.0
        best = _better(best, (fit, sp.gap, t_sigma))
    return best


def _gap_fit(arc: BurnArc, flown: BurnArc, about: FitResult, found: ManeuverSearch,
             gap: tuple[float, float], spread: bool = False) -> tuple[ImpulseFit, tuple[float, float], float] | None:
    """(fit, gap, time sigma) with one more burn in ``gap`` at the time the linearised profile
    about ``about`` puts it (:func:`_gap_starts`); None when the fit fails."""
    tb, t_sigma = burn_time_profile(flown, about, *gap)
    tbs = np.clip([tb - t_sigma, tb, tb + t_sigma], *gap) if spread else [tb]
    fit = _gap_starts(arc, about, np.unique(tbs), [x.t for x in found.burns])
    return None if fit is None else (fit, gap, t_sigma)


def _gap_starts(arc: BurnArc, about: FitResult, tbs: np.ndarray, known: list[float]) -> ImpulseFit | None:
    """The cheaper of the fits with one more burn at ``tbs`` (TU; the ``known`` burns' times too)
    from ``about``'s orbit with every observation in the first pass, and with those ``about``
    rejected left out of it (as :func:`~cistrack.least_squares.impulse_fit.refit_moved` does),
    each continued once when it stopped unconverged (:func:`_continued`); None when neither can
    be made. With a gross outlier in the first pass, survey fits of a 0.3 m/s burn stopped in a
    wrong minimum (dro, 1.77 m/s at capped cost 156.8; with the rejections left out 0.275 m/s at
    65.3), unconverged (halo: 85.8 against 41.8) or failed (a normal matrix not positive definite);
    the other way, a ballistic fit's rejections can be one whole side of the burn. (When ``about``
    rejected none the two are one fit, made once.)"""
    best, out = None, rejected_of(about)
    for rejected in (None, out) if out.any() else (None,):
        try:
            one = _continued(arc, fit_impulse(arc, about.state, about.epoch, tbs, known=known, rejected=rejected))
        except (FitError, PropagationError):
            continue
        if best is None or capped_cost(one.fit, arc.prior) < capped_cost(best.fit, arc.prior):
            best = one
    return best


def _continued(arc: BurnArc, one: ImpulseFit) -> ImpulseFit:
    """``one`` fitted once more from where it stopped (its delta-v and rejections carried) when it
    did not converge, the cheaper kept: the burn's test takes converged fits only."""
    if one.fit.converged:
        return one
    try:
        again = refit_moved(arc, one.fit, one.burns, one.new, one.searched.t)
    except (FitError, PropagationError, np.linalg.LinAlgError):
        return one
    cost = capped_cost(again.fit, arc.prior)
    if cost > capped_cost(one.fit, arc.prior):
        return one
    costs = np.where(one.candidates == one.searched.t, cost, one.costs)
    return replace(one, burns=again.burns, fit=again.fit, costs=costs)


def _better(best, one, margin: float = 0.0):
    """Of two (fit, gap, sigma), ``one`` when its fit costs more than ``margin`` less than
    ``best``'s (or ``best`` is None), else ``best`` (None for no fit)."""
    if one is None:
        return best
    return one if best is None or one[0].costs.min() < best[0].costs.min() - margin else best


def search_maneuvers(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, ballistic: FitResult,
                     options: FitOptions, say: Callable[[str], None] = lambda m: None,
                     prior: Any = None, again: ManeuverSearch | None = None) -> ManeuverSearch:
    """Burns that explain the arc ``ms`` better than the ``ballistic`` fit (module docstring).
    ``options`` are the fit's; the area-to-mass ratio is estimated with the burns only when the
    ballistic fit estimated it. ``prior``: (mean (6,), covariance (6, 6)) on the state at the
    ballistic fit's epoch, the one that fit was made with (None: none). ``again``: an earlier
    search of the same arc, ballistic fit, options and prior; this one then searches again with
    each burn fitted from where the orbits of its gap's two sides meet too (:func:`_next_burn`;
    slower), reusing that search's screened fits (:attr:`ManeuverSearch.screened`)."""
    opts = replace(options, area_to_mass="solve" if ballistic.parameter_names else "off")
    arc = BurnArc(dynamics, sensor, ms, opts, prior)
    found = ManeuverSearch(ballistic, dynamics, prior=prior, screened={} if again is None else again.screened,
                           ballistic=ballistic)
    for _ in range(MAX_BURNS):
        step = _next_burn(arc, found, split=again is not None)
        if step is None:
            break
        fit, window, t_sigma = step
        ev = burn_evidence(found.result, fit, FALSE_ALARM, found.prior)
        beyond = any_size(fit.searched)
        say(_tried_words(window, fit.searched, ev, beyond))
        if beyond and ev.accepted:
            found.unsized = (f"no impulsive burn of at most {MAX_BURN_MS:g} m/s in the gaps between the observations "
                             f"explains it: the burn that lowers the cost enough (by {ev.cost_drop:.3g}, "
                             f"{ev.cost_threshold:.3g} needed), in the gap {_gap_words(window)}, is one of any size "
                             f"({beyond}): these observations cannot tell a burn from outliers or another object")
        if beyond or not ev.accepted:
            break
        found = _add_burn(arc, found, fit, window, t_sigma)
    return found


def any_size(burn: BurnEstimate) -> str:
    """Why ``burn`` is one of any size, in words ("" when it is not): its delta-v or the sigma of its
    size beyond :data:`MAX_BURN_MS` (m/s; NaN counts as beyond). The observations then bound no
    burn there, and a figure of hundreds of km/s would describe nothing: six observations over three
    nights, one an outlier, had been "tried" with a burn of 85,501 m/s, and another kept one of
    466 +- 6e14 m/s between two exposures 14 minutes apart."""
    if not burn.magnitude_ms <= MAX_BURN_MS:
        return f"the fit puts it beyond {MAX_BURN_MS:g} m/s"
    if not burn.magnitude_sigma_ms <= MAX_BURN_MS:
        return f"the sigma of its size is beyond {MAX_BURN_MS:g} m/s"
    return ""


def _gap_words(window: tuple[float, float]) -> str:
    """The gap ``window`` (TU) as "a-b d" (days since the epoch)."""
    return f"{_utc_days(window[0]):.3f}-{_utc_days(window[1]):.3f} d"


def _tried_words(window: tuple[float, float], burn: BurnEstimate, ev, beyond: str) -> str:
    """The progress line of one burn tried in the gap ``window``: its size and the test against the
    fit without it (``ev``, a :class:`~cistrack.least_squares.impulse_fit.BurnEvidence`), or, for a
    burn of any size (``beyond``: :func:`any_size`'s words), no figure for its size."""
    test = f"cost drop {ev.cost_drop:.1f} (needs > {ev.cost_threshold:.1f})"
    if beyond:
        return (f"burn tried in the gap {_gap_words(window)}: one of any size ({beyond}, no burn of a cislunar object), "
                f"{test}, not kept: these observations cannot tell a burn there")
    return (f"burn tried in the gap {_gap_words(window)}: |dv| = {burn.magnitude_ms:.4f} +- "
            f"{burn.magnitude_sigma_ms:.4f} m/s, {test}, " + ("kept" if ev.accepted else "not kept"))


def _add_burn(arc: BurnArc, found: ManeuverSearch, fit: ImpulseFit, window: tuple[float, float],
              t_sigma: float) -> ManeuverSearch:
    """``found`` with ``fit``'s new burn (in the gap ``window``) added: its time refined and its
    uncertainty measured (:func:`_timed`), the burns found before keeping theirs."""
    t_new = fit.searched.t
    fit = _carried(_timed(arc, fit, t_sigma, found, window), found.burns)
    windows = found.windows + [window]
    order = np.argsort([x.t for x in found.burns] + [t_new], kind="stable")
    return ManeuverSearch(fit.fit, flown(arc.dynamics, fit.burns), fit.burns, [windows[int(i)] for i in order],
                          found.notes, found.prior, found.screened, found.ballistic)


def _timed(arc: BurnArc, fit: ImpulseFit, t_sigma: float, found: ManeuverSearch,
           window: tuple[float, float]) -> ImpulseFit:
    """``fit`` with the burn time refined in its gap and its uncertainty in the delta-v covariance
    (as it is when that fails: its burn then has no time uncertainty, ``dv_dt`` None, which the
    search's users must not report as a measured 0; the reason goes in ``found.notes``)."""
    try:
        return with_time_uncertainty(arc, fit, t_sigma, known=[x.t for x in found.burns], bounds=window)
    except (FitError, PropagationError) as exc:
        found.notes.append(f"burn at {_utc_days(fit.searched.t):.3f} d: its time's uncertainty was not measured ({exc})")
        return fit


def _carried(fit: ImpulseFit, before: list[BurnEstimate]) -> ImpulseFit:
    """``fit`` with the burns found before it (refitted jointly, their times held: t_sigma 0)
    given back their time uncertainty (:meth:`BurnEstimate.refitted`): without it a burn found
    first would be reported at its time +- 0 with a delta-v sigma that ignores the time's."""
    by_t = {x.t: x for x in before}
    burns = [by_t[b.t].refitted(b) if k != fit.new and b.t in by_t else b for k, b in enumerate(fit.burns)]
    return replace(fit, burns=burns)


def _utc_days(t: float) -> float:
    return float(units.tu_to_days(t))


@dataclass(frozen=True)
class RivalTime:
    """Another burn time the measurements allow (:func:`rival_time`).

    Attributes
    ----------
    t : float                 TU
    delta_v_ms : (3,) float   the delta-v fitted there, synodic m/s
    cost_delta : float        its fit's capped cost minus the estimate's
    chi2 : float              (dv - dv_est)^T C^-1 (dv - dv_est), C the sum of the two delta-v's covariances
    """

    t: float
    delta_v_ms: np.ndarray
    cost_delta: float
    chi2: float


def _candidates(times: np.ndarray, latest: float) -> np.ndarray:
    """:data:`GAP_POINTS` burn times (TU) inside each gap between ``times``, up to ``latest``."""
    fr = (np.arange(GAP_POINTS) + 0.5) / GAP_POINTS
    ts = np.array([a + f * (b - a) for a, b in _windows(times, []) for f in fr])
    return ts[ts <= latest]


def rival_time(arc: BurnArc, ballistic: FitResult, found: ManeuverSearch, burn: BurnEstimate,
               latest: float) -> RivalTime | None:
    """Another burn time up to ``latest`` (TU, the detection) that the measurements allow as well as
    ``burn``'s (its fit costs at most :data:`RIVAL_COST` more than the search's, ``found``, with its
    other burns held at their times) but with a delta-v the two estimates' uncertainties do not
    cover (chi-square of 3 dof in the sum of both covariances beyond its quantile at
    :data:`RIVAL_FALSE_ALARM`; the sum, as neither time is the true one): of those, the one whose fit costs
    least; None when there is none. ``arc``: the search's, its ``dynamics`` ballistic.

    The burn time's sigma comes from the cost's profile near its minimum, and the time's term in the
    delta-v covariance maps that sigma linearly; so every time the measurements allow should have a
    delta-v within about two sigma of the estimate. Where the profile is flat over several gaps
    (``example-1-maneuver`` seed 2, 3,000 particles, its second 0.1 m/s burn at 13.133 d estimated
    at 11.56 +- 0.68 d: a burn anywhere in 11.4-14.2 d costs at most 4.3 more) the delta-v fitted
    elsewhere differs from the estimate's by many sigma: neither the time nor the vector is
    determined. Candidates are :data:`GAP_POINTS` times in each gap, those the linearised screen
    about ``ballistic`` puts within :data:`RIVAL_COST` + :data:`RIVAL_SCREEN_SLACK` fitted in full."""
    ts = _candidates(arc.measurements.times, latest)
    if ts.size == 0:
        return None
    screen = screen_burn_times(arc, ballistic, np.append(ts, burn.t))
    near = ts[screen[:-1] <= min(screen.min(), screen[-1]) + RIVAL_COST + RIVAL_SCREEN_SLACK]
    others = [b.t for b in found.burns if b is not burn]
    best, limit = capped_cost(found.result, arc.prior), chi2_ppf(1.0 - RIVAL_FALSE_ALARM, 3)
    rival = None
    for tb in near:
        try:
            one = fit_impulses(arc, found.result.state, found.result.epoch, [*others, float(tb)])
            there = next(b for b in one.burns if b.t == float(tb))
            dv, both = there.delta_v_ms, burn.covariance_ms2 + there.covariance_ms2
            chi2 = float((dv - burn.delta_v_ms) @ np.linalg.solve(both, dv - burn.delta_v_ms))
        except (FitError, PropagationError, np.linalg.LinAlgError):
            continue
        cost = capped_cost(one.fit, arc.prior) - best
        if cost <= RIVAL_COST and chi2 > limit and (rival is None or cost < rival.cost_delta):
            rival = RivalTime(float(tb), dv, cost, chi2)
    return rival


NIGHT_GAP_HOURS = 3.0
"""A gap between observations at least this long separates observing sessions (nights)."""

FAR_POINTS = 3
"""Burn times fitted in each night's gap farther from a burn than its neighbours
(:func:`times_allowed`)."""
EDGE_MINUTES = (10.0, 30.0, 60.0)
"""Burn times fitted this many minutes from the end of the night's gap before a burn's window and
from the start of the one after it (:func:`_trial_times`): the gap's evenly spaced times lie hours
from the nights that bound it."""


def _trial_times(times: np.ndarray, window: tuple[float, float], taken: list[tuple[float, float]]) -> list[float]:
    """Burn times (TU): :data:`GAP_POINTS` times in ``window`` and in the nearest night's gap
    (at least :data:`NIGHT_GAP_HOURS`) before and after it (a burn between two tracklets of a night
    may as well lie after the night's last), :data:`EDGE_MINUTES` inside those two from their ends
    next to ``window`` (a burn shortly before a night's first tracklet may as well lie after that
    tracklet), and :data:`FAR_POINTS` in every
    other night's gap but those ``taken`` by other burns; empty when ``window`` is no gap of
    ``times``.

    Evenly spaced, the times nearest a night lie a twelfth of its gap away (two hours of a day's
    gap): a survey set's 1.5 m/s burn 53 minutes before a night's first tracklet was placed after
    that tracklet, 7.8 of its time sigmas late, and reported clean."""
    gaps, between = _windows(times, []), set(_gaps(times, []))
    k = next((i for i, g in enumerate(gaps) if np.isclose(g[0], window[0]) and np.isclose(g[1], window[1])), None)
    if k is None:
        return []
    night = [i for i, g in enumerate(gaps) if g in between and g[1] - g[0] >= units.hours_to_tu(NIGHT_GAP_HOURS)]
    before, after = max([i for i in night if i < k], default=k), min([i for i in night if i > k], default=k)
    out = []
    for i, (a, b) in enumerate(gaps):
        n = GAP_POINTS if i in (before, k, after) else FAR_POINTS if i in night and (a, b) not in taken else 0
        out += [float(a + f * (b - a)) for f in (np.arange(n) + 0.5) / max(n, 1)]
    edge = [float(units.seconds_to_tu(60.0 * m)) for m in EDGE_MINUTES]  # inside: a night's gap spans 3 h or more
    out += [gaps[before][1] - e for e in edge] if before != k else []
    return out + ([gaps[after][0] + e for e in edge] if after != k else [])


def times_allowed(arc: BurnArc, found: ManeuverSearch,
                  say: Callable[[str], None] = lambda m: None) -> tuple[ManeuverSearch, str]:
    """``found`` with each burn's time and delta-v uncertainty widened to reach the other times the
    arc allows as well, and "" ; or ``found`` and why its burn times are not the best, in words.
    ``say`` is told of a move (below) before the second check.

    Times in each burn's gap and in every night's gap (:func:`_trial_times`) are fitted in full (the
    other burns held). Those whose fit costs at most :data:`ALLOWED_COST` more than the search's
    (c; the profile's three-sigma interval) and lie beyond three of the burn's time sigmas are
    allowed times, each m = max(2, sqrt(c)) sigmas away: the time sigma becomes the largest of
    distance / m, and the delta-v covariance takes d d^T / m^2, d the allowed fit's delta-v minus
    the estimate's, for the d farthest in the estimate's covariance.

    A time whose fit costs more than :data:`RIVAL_COST` less means the search did not find the
    burn's time. The profile about the search's time can be a narrow minimum of several: an unseen
    survey set (0.5 m/s) had its burn timed 4.4 hours early +- 11 minutes (z -24.7) between two
    tracklets of a night, a burn after the night's last fitting as well; another (heo, seed 90) had
    its burn placed after the first night at 3.2 m/s, time z -16.9, where a burn in the five-day
    gap holding the true one fitted with a cost 29 lower. The burn is then moved there once
    (:func:`_moved`: refitted at the time the linearised profile about that better fit gives in
    its gap, its time's uncertainty measured again) and every burn is checked again from the moved
    fit; a time clearly better than the moved burn's as well means the time is not determined (the
    fit is not clean). A fit from the search's state does not reliably reach the true time's
    minimum (a burn moved without the second check had an unseen survey set reported clean at
    another wrong time)."""
    times = np.asarray(arc.measurements.times, dtype=float)
    checked, better = _checked(arc, found, times)
    if better is None:
        return checked, ""
    told = _told(found, *better)
    moved = _moved(arc, found, better, times)
    if moved is None:
        return found, f"{told}, and the fit with the burn moved there cannot be made: the burn's time is not determined"
    k, kept = better[0], {b.t for i, b in enumerate(found.burns) if i != better[0]}
    t_new = next(b.t for b in moved.burns if b.t not in kept)
    there, alone = f"{_utc_days(t_new):.3f} d", _sides_undetermined(arc, moved, t_new)
    if alone:
        return found, f"{told}, and moved there {alone}: the burn's time is not determined"
    say(f"{told}: the burn moved there, its time checked again")
    again, still = _checked(arc, moved, times)
    if still is not None:
        return found, f"{told}; moved there, {_told(moved, *still, 'the moved one')}: the burn's time is not determined"
    drop = capped_cost(found.result, arc.prior) - capped_cost(moved.result, arc.prior)
    found.notes.append(f"the time check moved burn {k + 1} from {_utc_days(found.burns[k].t):.3f} d to {there} "
                       f"(its fit's cost {drop:.1f} lower)")
    return again, ""


def _sides_undetermined(arc: BurnArc, moved: ManeuverSearch, tb: float) -> str:
    """"" when the observations before the burn at ``tb`` (TU) and those after it, each fitted
    alone as a ballistic arc from ``moved``'s orbit, converge with every direction observable; else
    which side does not, in words. Where both sides determine their orbits, the burn's time and
    delta-v are where those orbits meet, and the cost's profile over burn times has one clear
    minimum; where one does not, the profile over a long gap can have several at delta-v of any
    size (an unseen survey set's 0.5 m/s burn, two tracklets before it and three nights after, both
    sides unobservable: moved to a time 11.8 cheaper, 0.83 m/s, 9 of its time sigmas early)."""
    ms = arc.measurements
    for side, sel, edge in (("before", ms.times < tb, -1), ("after", ms.times > tb, 0)):
        sub = ms.subset(sel)
        if sub.times.size == 0:
            return f"no observation lies {side} it"
        t0 = float(sub.times[edge])
        try:
            x = arc_states(moved.dynamics, moved.result.state, moved.result.epoch, np.array([t0]))[0]
            with warnings.catch_warnings():  # the weak direction is this check's answer, not a warning
                warnings.simplefilter("ignore", UnobservableWarning)
                fit = fit_orbit(arc.dynamics, arc.sensor, sub, x, t0, options=arc.options)
        except (FitError, PropagationError, np.linalg.LinAlgError) as exc:
            return f"the {sub.times.size} observations {side} it cannot be fitted alone ({exc})"
        if not fit.converged or fit.unobservable:
            return (f"the {sub.times.size} observations {side} it do not determine an orbit alone "
                    f"({'a direction unobservable' if fit.converged else 'their fit does not converge'})")
    return ""


def _told(found: ManeuverSearch, k: int, better: tuple[float, float, ImpulseFit], whose: str = "the search's") -> str:
    """In words: burn ``k`` of ``found`` (``whose``) has a ``better`` (cost, time TU, fit) trial time."""
    return (f"a burn at {_utc_days(better[1]):.3f} d fits the arc better than {whose} at "
            f"{_utc_days(found.burns[k].t):.3f} d (its cost {-better[0]:.1f} lower)")


def _checked(arc: BurnArc, found: ManeuverSearch, times: np.ndarray):
    """(``found`` with its burns widened to the times allowed, None); or (``found``, (k, (cost,
    time TU, fit))) for the first burn k that a trial time fits more than :data:`RIVAL_COST`
    better."""
    burns, base = list(found.burns), capped_cost(found.result, arc.prior)
    for k, (b, window) in enumerate(zip(found.burns, found.windows)):
        allowed, better = _allowed_times(arc, found, (b, window), times, base)
        if better is not None:
            return found, (k, better)
        if allowed:
            burns[k] = _widened(b, allowed)
    return replace(found, burns=burns), None


def _moved(arc: BurnArc, found: ManeuverSearch, better: tuple[int, tuple[float, float, ImpulseFit]],
           times: np.ndarray) -> ManeuverSearch | None:
    """``found`` with burn k moved into the gap of its ``better`` trial (k, (cost, time TU, fit)):
    fitted at that time and at the time the linearised profile about the trial's orbit gives in
    its gap (:func:`_gap_starts`, from the trial's orbit), the better kept, its time refined and
    measured (:func:`_add_burn`); None when no fit can be made."""
    k, (_, tb, trial) = better
    window = next((w for w in _windows(times, []) if w[0] <= tb <= w[1]), None)
    if window is None:
        return None
    others = [b for i, b in enumerate(found.burns) if i != k]
    rest = ManeuverSearch(found.result, flown(arc.dynamics, others), others,
                          [w for i, w in enumerate(found.windows) if i != k], found.notes, found.prior, found.screened,
                          found.ballistic)
    about = replace(found.result, state=trial.fit.state)
    try:
        t_p, t_sigma = burn_time_profile(replace(arc, dynamics=rest.dynamics), about, *window)
    except (FitError, PropagationError, np.linalg.LinAlgError):
        return None
    fit = _gap_starts(arc, trial.fit, np.unique([t_p, tb]), [b.t for b in others])
    return None if fit is None else _add_burn(arc, rest, fit, window, t_sigma)


def _allowed_times(arc: BurnArc, found: ManeuverSearch, burn: tuple[BurnEstimate, tuple[float, float]],
                   times: np.ndarray, base: float):
    """([(time TU, delta-v m/s (3,), sigmas away)] the arc allows for ``burn`` (estimate, gap) as
    well, far from its time, None); or ([], (cost, time TU, fit)) of the trial time that fits best
    when one fits more than :data:`RIVAL_COST` better (:func:`times_allowed`). The trial times are
    :func:`_trial_times` and those of :func:`_walked` and :func:`_from_ballistic`."""
    b, window = burn
    taken = [w for w in found.windows if w != window]
    tried = [t for t in (_trial(arc, found, b, float(tb), base) for tb in _trial_times(times, window, taken)) if t]
    tried += _walked(arc, found, b, window, base) + _from_ballistic(arc, found, b, window, base)
    better = [t for t in tried if t[1] < -RIVAL_COST]
    if better:
        tb, cost, one = min(better, key=lambda t: t[1])
        return [], (cost, tb, one)
    return [(tb, next(x.delta_v_ms for x in one.burns if x.t == tb), max(2.0, float(np.sqrt(max(cost, 0.0)))))
            for tb, cost, one in tried if cost <= ALLOWED_COST and abs(tb - b.t) > 3.0 * b.t_sigma], None


def _trial(arc: BurnArc, found: ManeuverSearch, b: BurnEstimate, tb: float, base: float):
    """(``tb``, the capped cost of the arc's fit with ``found``'s burn ``b`` moved to ``tb`` (TU)
    minus ``base``, that fit), the other burns held at their times; None when the fit cannot be
    made. Every delta-v starts from ``found``'s: from zero, fits with a halo orbit's 0.5 m/s burn
    moved by five minutes had run off to 40 m/s at costs of 1e10, and the check saw no time but
    the search's (a survey set reported clean with its burn two hours off)."""
    k = next(i for i, x in enumerate(found.burns) if x is b)
    try:
        one = refit_moved(arc, found.result, found.burns, k, tb)
    except (FitError, PropagationError, np.linalg.LinAlgError):
        return None
    return tb, capped_cost(one.fit, arc.prior) - base, one


def _from_ballistic(arc: BurnArc, found: ManeuverSearch, b: BurnEstimate, window: tuple[float, float],
                    base: float) -> list:
    """[(time TU, cost, fit)] of the fits with ``found``'s burn ``b`` at :data:`GAP_POINTS` times in
    its own gap ``window`` (TU) from the ballistic fit (its state, its rejections left out of the
    first pass, ``b``'s delta-v from zero; the other burns from theirs), cost minus ``base``; none
    when the search holds no ballistic fit. A trial refitted from the search's fit keeps the
    minimum that fit lies in: survey fits of a 0.3 m/s burn kept 0.92 m/s in a one-day gap (and
    3.2 m/s in another) with a gross outlier among their observations, and every trial from them
    stayed there, while fits from the ballistic orbit with its rejections left out found 0.29-0.33
    m/s 18-22 cheaper in the same gap."""
    if found.ballistic is None:
        return []
    k = next(i for i, x in enumerate(found.burns) if x is b)
    burns = [replace(x, delta_v_ms=np.zeros(3)) if i == k else x for i, x in enumerate(found.burns)]
    out = []
    for tb in (window[0] + (np.arange(GAP_POINTS) + 0.5) / GAP_POINTS * (window[1] - window[0])).tolist():
        try:
            one = refit_moved(arc, found.ballistic, burns, k, tb)
        except (FitError, PropagationError, np.linalg.LinAlgError):
            continue
        out.append((tb, capped_cost(one.fit, arc.prior) - base, one))
    return out


WALK_SIGMAS = 4.0
"""The first trial times of :func:`_walked` lie this many of the burn's time sigmas either side of it."""
WALK_MIN_MINUTES = 5.0
"""... or this many minutes, when that is farther."""
WALK_STEPS = 12
"""At most this many trial times each side, each twice as far as the one before."""


def _walked(arc: BurnArc, found: ManeuverSearch, b: BurnEstimate, window: tuple[float, float],
            base: float) -> list:
    """[(time TU, cost, fit)] of :func:`_trial` either side of ``b``'s time, the first
    max(:data:`WALK_SIGMAS` time sigmas, :data:`WALK_MIN_MINUTES`) away and each next twice as
    far (kept inside ``window``), each side until a fit costs more than :data:`ALLOWED_COST`, the
    window ends or :data:`WALK_STEPS` were made.

    The time sigma comes from a parabola through three fits within about a sigma of the time
    (:func:`~cistrack.least_squares.impulse_fit.with_time_uncertainty`); where the cost's profile is
    flatter farther out, times many of those sigmas away are allowed too. The night gaps'
    :func:`_trial_times` are hours apart and do not see it: an unseen survey set's 1 m/s burn
    (heo) was timed +- 7.7 minutes and reported clean 40 minutes (5.3 sigmas) early, the fit at
    twelve sigmas costing 4.3 more, the truth far outside the orbit's covariance; another's (halo,
    0.5 m/s) +- 0.013 s, two hours early, from a parabola through costs that differed by their
    convergence's noise."""
    out = []
    first = max(WALK_SIGMAS * b.t_sigma, float(units.seconds_to_tu(60.0 * WALK_MIN_MINUTES))) if b.t_sigma > 0 else 0.0
    for side in (-1.0, 1.0) if first > 0 else ():
        for j in range(WALK_STEPS):
            tb = float(min(max(b.t + side * first * 2.0 ** j, window[0]), window[1]))
            if tb == b.t:  # the burn sits at the window's edge: no room on this side
                break
            got = _trial(arc, found, b, tb, base)
            if got is None:
                break
            out.append(got)
            if got[1] > ALLOWED_COST or tb in window:
                break
    return out


def _widened(b: BurnEstimate, allowed: list[tuple[float, np.ndarray, float]]) -> BurnEstimate:
    """``b`` with each allowed (time, delta-v, m) m sigmas from its estimate (:func:`times_allowed`);
    its ``reach`` the (time, m) that sets the time's sigma."""
    t_far, _, m_far = max(allowed, key=lambda a: abs(a[0] - b.t) / a[2])
    sigma = max(b.t_sigma, abs(t_far - b.t) / m_far)
    d = [(np.asarray(dv, dtype=float) - b.delta_v_ms) / m for _, dv, m in allowed]
    try:
        far = max(d, key=lambda x: float(x @ np.linalg.solve(b.covariance_ms2, x)))
    except np.linalg.LinAlgError:
        far = max(d, key=lambda x: float(x @ x))
    return replace(b, covariance_ms2=b.covariance_ms2 + np.outer(far, far), t_sigma=sigma, widened=True,
                   reach=(float(t_far), float(m_far)) if sigma > b.t_sigma else b.reach)
