"""Maneuvers in ``cistrack fit``: a fit that an impulsive burn explains is never a clean "converged".

A ballistic fit that looks like an object that maneuvered (a contiguous block of rejections, a
large RMS, no convergence: :func:`cistrack.least_squares.burn_search.suspicion`) is searched for
burns (:func:`cistrack.least_squares.burn_search.search_maneuvers`); each burn kept becomes an entry
of ``fit.json``'s ``maneuvers`` (:func:`maneuver_record`) and the fit the one with the burns.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, NamedTuple

import numpy as np

from cistrack import units
from cistrack.least_squares.options import AREA_TO_MASS
from cistrack.least_squares.impulse_fit import BurnEstimate

__all__ = ["maneuver_record", "site_left_out", "least_significance", "MIN_SEARCH_ARC_DAYS", "MIN_BURN_SIGMAS", "MAX_TIME_TRADE"]

MIN_BURN_SIGMAS = 3.0
"""A burn the fit reports with fewer than two nights of observations on one side
(:func:`_one_night_side`; with more, :data:`MIN_TESTED_BURN_SIGMAS`) has a magnitude of at least this many of its sigmas at every burn time
within 3 of its time sigmas (:func:`least_significance`): mis-identified tracklets at the end of a survey arc had been fitted with a
532 +- 24,668 m/s burn and reported "converged", the truth 3,454 km away. (A run's maneuver watch,
which detects a burn before estimating it, keeps smaller ones and judges them by its own checks.)"""

MAX_TIME_TRADE = 2.0
"""A burn the fit reports needs a delta-v that changes by at most this many times its size within
one sigma of its time (:func:`_time_trade`): beyond, the linear time term describes nothing and the
arc measures neither. An unseen survey set's 0.5 m/s burn came out 1.1 +- 1.2 m/s, its time +- 20
hours, 27 m/s per sigma of time (the truth at Mahalanobis^2 519); the dense campaign's 0.3 m/s
burn trades 1.3 times its size per sigma and is measured. (A burn whose time's sigma was widened to
other allowed times is judged by its whole covariance instead: :func:`_significance`.)"""

MIN_SEARCH_ARC_DAYS = 0.5
"""The shortest arc searched for burns (12 hours): within one night a burn's three parameters fit an
outlier as readily as a maneuver (one site's night of 6 observations with one gross outlier took a
912 +- 626 m/s burn between two exposures 12 minutes apart, and predicted an Earth impact 5 hours
later). A suspect fit of a shorter arc is reported as not clean, with no burn searched."""


def _days(t: float) -> float:
    return float(units.tu_to_days(t))


def maneuver_record(burn: BurnEstimate, window: tuple[float, float], first_after: float, epoch) -> dict:
    """One ``maneuvers`` entry of ``fit.json``: ``t_days`` (the first observation that shows the
    burn), ``t_burn_days`` (the estimated burn time), ``t_burn_window_days`` (the gap it lies in),
    all days since the scenario epoch, with their UTC; ``delta_v_ms`` and ``delta_v_sigma_ms``
    (magnitude, m/s), ``delta_v_vector_ms`` and its ``delta_v_covariance_ms2`` (synodic components)."""
    return {
        "t_days": _days(first_after), "t_burn_days": _days(burn.t),
        "t_burn_window_days": [_days(window[0]), _days(window[1])],
        "t_burn_utc": units.format_utc(units.tu_to_utc(epoch, burn.t)),
        "t_burn_window_utc": [units.format_utc(units.tu_to_utc(epoch, w)) for w in window],
        "t_burn_sigma_days": _days(burn.t_sigma),
        "delta_v_ms": burn.magnitude_ms, "delta_v_sigma_ms": burn.magnitude_sigma_ms,
        "delta_v_vector_ms": [float(v) for v in burn.delta_v_ms], "frame": "synodic",
        "delta_v_covariance_ms2": np.asarray(burn.covariance_ms2, dtype=float).tolist(),
        "significance_chi2": burn.significance,
    }


def add_maneuvers(one, say) -> None:
    """Search the fit of ``one`` (an :class:`~cistrack.fitting.from_observations.ObjectFit`) for burns
    when it looks like an object that maneuvered (:func:`~cistrack.least_squares.burn_search.suspicion`).

    With burns kept, ``one.result`` becomes the fit with them, its state at an epoch after the last
    burn (:func:`_after_burns`) and its covariance the state's marginal one (the burns' uncertainty
    in it, their delta-v no longer among its parameters: every later step predicts forward of the
    burns with the run's ballistic model); ``one.dynamics`` is the model with the burns (for the
    residuals of the whole arc) and ``one.maneuvers`` their records. A suspect fit that no burn
    explains, or that is still suspect with the burns found, is searched once more with each burn
    started where the orbits fitted to either side of a gap meet
    (:mod:`cistrack.least_squares.split_start`); when that is not clean either, it is not reported
    as converged (and the burns are not reported): its messages say the first search's reason, and
    radiation pressure when that fits it cleanly too (:mod:`cistrack.fitting.pressure_rescue`).
    A fit suspect only by the linearised screen (:func:`~cistrack.least_squares.burn_search.screen_suspicion`)
    is searched once, and stays as it was unless that search measures its burns, its messages saying
    why (a dense campaign's 1 cm/s burn: 0.07 +- 0.06 m/s 1.7 days before it passes the burn test).
    First, a fit that one site's clock offset explains (:func:`_clock_explains`) is not searched:
    not clean, its words naming the site and the offset, unless the offset moves a clean fit's orbit
    within its covariance."""
    from cistrack.least_squares.burn_search import flown

    r = one.result
    if r is None or one.run is None:
        return
    ctx = one.run.context
    times = np.asarray(ctx.measurements.times, dtype=float)
    span = _days(float(times.max() - times.min())) if times.size else 0.0
    why, screened = _suspected(ctx, one, span)
    if _clock_explains(ctx, one, r, why) or not why or _too_short(one, r, why, span):
        return
    say(f"{one.designation}: the ballistic fit looks like a maneuver ({why}); searching for burns")
    outcome = _measured(ctx, one, say)
    if screened and outcome.doubt:
        one.result = replace(r, messages=tuple(r.messages) + (
            f"searched for burns ({why}): {outcome.doubt}; the ballistic fit is kept",))
        return
    if outcome.doubt:
        say(f"{one.designation}: not measured ({outcome.doubt}); searching again with each burn started where the "
            "orbits fitted to either side of a gap meet")
        outcome = _retried(ctx, one, outcome, say)
    found, fit, burns, doubt = outcome.found, outcome.fit, outcome.burns, outcome.doubt
    if doubt:
        _not_measured(ctx, one, (r, why), doubt, say)
        return
    fit, burns = _ratio_as_set(ctx, one, found, fit, burns)
    if _clock_passes_for_burns(ctx, one, (r, why), fit, burns):
        return
    one.maneuvers = [maneuver_record(b, w, float(times[times > b.t][0]), one.scenario.epoch)
                     for b, w in zip(burns, found.windows)]
    one.dynamics = flown(ctx.dynamics, burns)
    text = "; ".join(f"a burn of {m['delta_v_ms']:.3f} +- {m['delta_v_sigma_ms']:.3f} m/s at {m['t_burn_utc'][:16]}"
                     for m in one.maneuvers)
    moves = [n for n in found.notes if n.startswith("the time check moved")]
    one.result = replace(_without_burns(fit), messages=tuple(fit.messages) + (
        f"the ballistic fit looked like a maneuver ({why}); fitted with {len(burns)} impulsive burn(s): {text}"
        + _size_words(fit, burns),
        *moves))


def _not_measured(ctx, one, ballistic, doubt: str, say) -> None:
    """``one``'s result when its ballistic fit (``ballistic``: the fit and why it looked like a
    maneuver) is one no burn measured (``doubt``): not clean, its words naming a site whose
    observations alone the others do not fit (:func:`site_left_out`) and radiation pressure when
    that fits it cleanly too (:func:`_pressure_words`)."""
    r, why = ballistic
    site = site_left_out(ctx, one, r, say)
    pressure = _pressure_words(ctx, one, r, say)
    one.result = replace(_ratio_unclean(r), converged=False, messages=tuple(r.messages) + (
        f"{_unclean(one, r, why)}, and {doubt}" + (f"; {site}" if site else "") + pressure,))


def _pressure_words(ctx, one, r, say) -> str:
    """"; radiation pressure ... fits it cleanly too ..." when the fit of ``one``'s observations with
    C_R A/m solved for is clean and passes "auto"'s test (:mod:`cistrack.fitting.pressure_rescue`),
    else "". The fit is not replaced: on a survey set with a 0.3 m/s burn the ratio fitted cleanly
    (0.19 m^2/kg, 13 sigma) and that orbit missed the truth by Mahalanobis^2 660,000; the arc cannot
    tell the two apart, the user can (an object's ratio is known, or fits a longer arc)."""
    from cistrack.fitting.pressure_rescue import pressure_explains

    seven = pressure_explains(ctx, one, r, say)
    if seven is None:
        return ""
    value, sigma = seven.parameter(AREA_TO_MASS)
    return (f"; radiation pressure fits it cleanly too (C_R A/m = {value:.3g} +- {sigma:.2g} m^2/kg; "
            "--set fit.area_to_mass=solve fits it so): these observations cannot tell it from a burn")


def _clock_explains(ctx, one, r, why: str) -> bool:
    """Whether one site's clock offset explains ``r``, the ballistic fit of ``one``
    (:func:`~cistrack.fitting.site_clock.clock_off`). Then ``one.result`` is ``r`` with the words:
    not clean when ``r`` looks like a maneuver (``why``) or the correction moves its orbit beyond
    :data:`~cistrack.fitting.site_clock.MOVED_BOUND` in its covariance; else kept, the clock a note
    and its covariance widened by the offset (:func:`~cistrack.fitting.site_clock.consider_spread`)."""
    from cistrack.fitting.site_clock import MOVED_BOUND, clock_off

    finding = clock_off(ctx, one, r)
    if finding is None:
        return False
    if why or finding.moved_m2 > MOVED_BOUND:
        also = f"; it looks like an object that maneuvered too ({why}): no burn was searched" if why else ""
        one.result = replace(_ratio_unclean(r), converged=False, messages=tuple(r.messages) + (
            f"not a clean fit: {finding.words}{also}",))
    else:
        one.result = replace(_widened(r, finding.spread), messages=tuple(r.messages) + (
            f"{finding.words}, within the {MOVED_BOUND:g} it allows: the fit is kept as it is, its covariance widened "
            "by the offset (its size and its sigma) along the orbit's sensitivity to it",))
    return True


def _widened(r, spread: np.ndarray):
    """``r`` with ``spread`` (6, 6) LU, VU added to its state covariance (and to that block of its
    full covariance)."""
    full = r.full_covariance
    if full is not None:
        full = np.array(full, dtype=float)
        full[:6, :6] += spread
    return replace(r, covariance=np.asarray(r.covariance, dtype=float) + spread, full_covariance=full)


def _clock_passes_for_burns(ctx, one, suspect: tuple, fit, burns) -> bool:
    """Whether a site's clock passes for burns in ``fit``, the fit with the ``burns`` the search kept
    (:func:`_clock_with_burns`): then ``one.result`` is the ballistic fit of ``suspect`` (the fit,
    why it looks like a maneuver), not clean, saying so."""
    r, why = suspect
    clock = _clock_with_burns(ctx, fit, burns)
    if clock:
        one.result = replace(_ratio_unclean(r), converged=False, messages=tuple(r.messages) + (
            f"{_unclean(one, r, why)}; {clock}",))
    return bool(clock)


def _clock_with_burns(ctx, fit, burns) -> str:
    """Words when a site's clock offset, fitted with the burns the search kept, explains one of
    them ("" when none does): for each site the clock test can test
    (:func:`~cistrack.least_squares.site_timing.site_timings` on ``fit``, the burns' delta-v
    projected out with the state), each burn's delta-v with that site's offset estimated too
    (:func:`_burn_with_clock`), and its chi-square from none (3 degrees of freedom) against the
    burn test's limit; or a site's offset significant beside the burns. A 1 m/s burn and one site's
    times 20 s late had been fitted with three burns, two invented (5 and 9 sigma: they absorbed
    the clock), and reported "converged", the truth 162 km from the exported orbit."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.burn_search import FALSE_ALARM, flown
    from cistrack.least_squares.chi_square import chi2_ppf
    from cistrack.least_squares.site_timing import site_timings, timing_limit

    names = tuple(n for n in fit.parameter_names if n.startswith("delta_v_"))
    try:
        timings = site_timings(flown(ctx.dynamics, burns), ctx.sensor, ctx.measurements, fit, also=names)
    except (CistrackError, np.linalg.LinAlgError):
        return ""
    limit = chi2_ppf(1.0 - FALSE_ALARM, 3)
    weak = [(t, [(k, c) for k, c in enumerate(_burn_with_clock(fit, names, t)) if c < limit]) for t in timings]
    t, gone = max(weak, key=lambda w: (len(w[1]), -sum(c for _, c in w[1])), default=(None, []))
    if gone:
        which = ", ".join(f"{k + 1} ({burns[k].magnitude_ms:.3g} +- {burns[k].magnitude_sigma_ms:.2g} m/s)" for k, _ in gone)
        return (f"fitted with {_count(len(burns), 'burn')}, but with site {t.site}'s clock offset fitted too "
                f"({t.offset_s:+.3g} +- {t.sigma_s:.2g} s) {'burns' if len(gone) > 1 else 'burn'} {which} no longer "
                f"{'differ' if len(gone) > 1 else 'differs'} from none (chi-square {', '.join(f'{c:.1f}' for _, c in gone)} "
                f"for 3 degrees of freedom, {limit:.1f} needed): a clock or position error at {t.site} can pass for "
                "burns, so none is reported as a maneuver")
    if timings and timings[0].drop > timing_limit():
        t = timings[0]
        return (f"fitted with {_count(len(burns), 'burn')}, site {t.site}'s times still look {abs(t.offset_s):.3g} +- "
                f"{t.sigma_s:.2g} s {'late' if t.offset_s > 0 else 'early'} against the other sites' (the offset "
                f"removes a chi-square of {t.drop:.0f}; {timing_limit():.1f} is noise at 1e-4): a clock or position "
                f"error at {t.site}, which burns can pass for, so they are not reported as maneuvers")
    return ""


def _burn_with_clock(fit, names: tuple[str, ...], timing) -> list[float]:
    """Each burn's chi-square from none (3 dof) in ``fit`` with ``timing``'s site offset estimated
    too: its delta-v and covariance moved by the offset's linearised absorption
    (:class:`~cistrack.least_squares.site_timing.SiteTiming`)."""
    from cistrack.least_squares.impulse_fit import dv_names

    out = []
    for k in range(len(names) // 3):
        idx = [names.index(n) for n in dv_names(k)]
        g = np.asarray(timing.absorbed_per_s, dtype=float)[[6 + i for i in idx]]
        dv = np.asarray(fit.parameters, dtype=float)[[list(fit.parameter_names).index(n) for n in dv_names(k)]]
        dv = dv - g * timing.offset_s
        cov = _dv_block(fit, k) + np.outer(g, g) * timing.sigma_s ** 2
        out.append(float(dv @ np.linalg.solve(cov, dv)))
    return out


def _too_short(one, r, why: str, span: float) -> bool:
    """Whether the arc of ``span`` days is too short to search for burns: then ``one.result`` is
    ``r`` (suspect for ``why``), not clean, saying so."""
    if span >= MIN_SEARCH_ARC_DAYS:
        return False
    one.result = replace(r, converged=False, messages=tuple(r.messages) + (
        f"{_unclean(one, r, why)}; an arc of {span * 24.0:.3g} h "
        f"(under {MIN_SEARCH_ARC_DAYS * 24.0:g} h) cannot tell a burn from outliers or wrong weights, so no burn "
        "was searched",))
    return True


def _ratio_unclean(r):
    """``r`` with its area-to-mass decision saying that the fit is not clean: a ratio estimated on
    the ballistic fit of an object that maneuvered may be absorbing the burn (0.54 m^2/kg, 200 of
    its sigmas, on a survey set with a 1 m/s burn and no radiation pressure)."""
    if AREA_TO_MASS not in r.parameter_names:
        return r
    words = "in a fit that is not clean: the ratio may be absorbing what the ballistic orbit does not explain (a maneuver)"
    return replace(r, area_to_mass_decision="; ".join(x for x in (r.area_to_mass_decision, words) if x))


def _ratio_as_set(ctx, one, found, fit, burns):
    """(fit, burns) with the area-to-mass ratio as ``fit.area_to_mass`` says: the search estimates it
    with the burns whenever the ballistic fit did, which under "auto" may have been the burn
    absorbed (a survey set with a 0.5 m/s burn and no radiation pressure: -0.0055 +- 0.0022 m^2/kg
    with the burn, exported and predicted with, worded "as asked (area_to_mass = 'solve')"). Under
    "auto" a ratio that :func:`~cistrack.least_squares.area_to_mass.estimate_doubt` doubts is
    dropped: the burns are refitted at their times without it, keeping their time uncertainty
    (when that refit fails or leaves a burn in doubt, the fit with the ratio stays, saying so)."""
    from cistrack.least_squares.area_to_mass import estimate_doubt

    if AREA_TO_MASS not in fit.parameter_names:  # the ballistic fit's decision not to estimate it stands
        return replace(fit, area_to_mass_decision=fit.area_to_mass_decision or one.result.area_to_mass_decision), burns
    if one.choices.options.area_to_mass != "auto":
        return fit, burns
    doubt = estimate_doubt(fit)
    value, sigma = fit.parameter(AREA_TO_MASS)
    if doubt is None:
        return replace(fit, area_to_mass_decision=f"estimated with the burns ({value:.4g} +- {sigma:.2g} m^2/kg)"), burns
    six, burns6, failed = _without_ratio(ctx, found, burns)
    if failed or _burn_doubt(six, burns6):
        return replace(fit, area_to_mass_decision=f"estimated with the burns, but the {doubt}; without it "
                                                  f"{failed or _burn_doubt(six, burns6)}"), burns
    return replace(six, area_to_mass_decision=f"not estimated: with the burns fitted, the {doubt}"), burns6


def _without_ratio(ctx, found, burns):
    """(fit, burns, "") of the search's burns refitted at their times without the area-to-mass
    ratio (:func:`_completed`), or (None, [], why) when that cannot be made."""
    from cistrack.errors import PropagationError
    from cistrack.least_squares.burn_search import burn_fit_options, flown
    from cistrack.least_squares.errors import FitError
    from cistrack.least_squares.impulse_fit import BurnArc, fit_impulses
    from cistrack.least_squares.options import FitOptions

    arc = BurnArc(ctx.dynamics, ctx.sensor, ctx.measurements, burn_fit_options(FitOptions(area_to_mass="off")),
                  found.prior)
    try:
        again = fit_impulses(arc, found.result.state, found.result.epoch, [b.t for b in found.burns],
                             [b.delta_v_ms for b in found.burns])
    except (FitError, PropagationError) as exc:
        return None, [], f"the fit without it failed ({exc})"
    kept = [b.refitted(n) for b, n in zip(found.burns, again.burns)]
    return _completed(ctx, replace(found, result=again.fit, dynamics=flown(ctx.dynamics, kept), burns=kept))


def _suspected(ctx, one, span: float) -> tuple[str, bool]:
    """(why ``one``'s ballistic fit looks like an object that maneuvered, whether only the
    linearised screen says so): :func:`~cistrack.least_squares.burn_search.suspicion`, else on an
    arc of at least :data:`MIN_SEARCH_ARC_DAYS`
    :func:`~cistrack.least_squares.burn_search.screen_suspicion` ("" when neither does)."""
    from cistrack.least_squares.burn_search import screen_suspicion, suspicion

    why = suspicion(one.result)
    if why or span < MIN_SEARCH_ARC_DAYS:
        return why, False
    why = screen_suspicion(ctx.dynamics, ctx.sensor, ctx.measurements, one.result, one.choices.options)
    return why, bool(why)


def _capped_alone(result) -> int:
    """How many observations ``result`` uses although their chi-square exceeds its rejection
    threshold (the cap on rejections, ``max_reject_fraction``, kept them), or 0 when one of them
    shares its night (observations within
    :data:`~cistrack.least_squares.burn_search.END_NIGHT_GAP_HOURS`) with observations whose median
    chi-square is above the threshold too: a whole night off is a maneuver's or a site's sign, not
    outliers the cap kept (a 3 m/s burn's first night sat 126 sigma off; its 2 kept observations had
    been named first as what may pull the fit)."""
    from cistrack.least_squares.burn_search import END_NIGHT_GAP_HOURS

    res = result.residuals
    t, chi2 = np.asarray(res.times, dtype=float), np.asarray(res.chi2, dtype=float)
    kept = np.flatnonzero(~np.asarray(res.rejected, dtype=bool) & (chi2 > result.rejection_threshold))
    night = units.hours_to_tu(END_NIGHT_GAP_HOURS)
    for k in kept:
        mates = (np.abs(t - t[k]) < night) & (np.arange(t.size) != k)
        if mates.any() and np.median(chi2[mates]) > result.rejection_threshold:
            return 0
    return int(kept.size)


SITE_SPAN_SHARE = 0.9
"""A site is left out (:func:`site_left_out`) only when the others' observations span at least this
share of the arc: a site that alone saw one end of it would take a burn with it."""


def site_left_out(ctx, one, r, say=None) -> str:
    """Words naming the one site without whose observations the rest fit cleanly, and any site that
    could not be left out ("" when none or several do): each site with three observations or more left out in turn, the others (spanning
    :data:`SITE_SPAN_SHARE` of the arc, from two sites or more) fitted (:func:`_left_out_fit`) with
    the fit's options and the share of rejections it applied, clean when converged with nothing
    :func:`~cistrack.least_squares.burn_search.suspicion` or
    :func:`~cistrack.least_squares.burn_search.screen_suspicion` names. One site's 30 s clock
    offset, or a wrong site code, had been reported only as "an object that maneuvered"; and one
    site's ballistic fit had absorbed a real 1 m/s burn, blaming the other site's lone tracklet. The
    words offer both explanations: on 3 of 34 survey sets with a real 0.3-1 m/s burn and no site
    error the others' observations alone fit cleanly too. A site that could not be left out (the
    others short of the span) is named beside the one that was: W68's rows filed as X03 had been
    blamed on 809, the one site tested and the one right."""
    from cistrack.least_squares.burn_search import screen_suspicion, suspicion

    ms = ctx.measurements
    t, sites = np.asarray(ms.times, dtype=float), np.asarray(ms.sites).astype(str)
    opts = one.choices.options
    if one.reject_fraction is not None:
        opts = replace(opts, max_reject_fraction=one.reject_fraction)
    clean, untested = [], []
    for x in [x for x in np.unique(sites) if x and np.sum(sites == x) >= 3]:
        keep = sites != x
        if keep.sum() < 6 or len(set(sites[keep])) < 2 or np.ptp(t[keep]) < SITE_SPAN_SHARE * np.ptp(t):
            untested.append(x)
            continue
        (say or (lambda m: None))(f"{one.designation}: fitting the observations of every site but {x}")
        sub = ms.subset(keep)
        f = _left_out_fit(ctx, sub, r, opts)
        if f is not None and not suspicion(f) and not screen_suspicion(ctx.dynamics, ctx.sensor, sub, f, opts):
            clean.append((x, int(np.sum(~keep)), f.rms))
    if len(clean) != 1:
        return ""
    x, n, rms = clean[0]
    if untested:  # one of them may be the site in error: the others' fit without it was never tried
        return (f"without site {x}'s {n} observations the others fit cleanly (weighted RMS {rms:.2f}), but "
                f"{_sites_words(untested)} could not be left out in turn (the others' observations do not span "
                f"{100 * SITE_SPAN_SHARE:.0f} % of the arc): a clock, position or stated-uncertainty error at "
                f"{' or '.join([x, *untested])}, or a burn the other sites' observations alone do not show?")
    return (f"without site {x}'s {n} observations the others fit cleanly (weighted RMS {rms:.2f}): a clock, position or "
            f"stated-uncertainty error at {x}, or a burn the other sites' observations alone do not show?")


def _sites_words(sites: list[str]) -> str:
    return f"site {sites[0]}" if len(sites) == 1 else "sites " + ", ".join(sites)


def _left_out_fit(ctx, sub, r, opts):
    """The converged fit of ``sub`` (the observations of every site but one) from ``r``'s orbit, or,
    when that does not converge, from a fresh IOD of ``sub`` (seeded by the run's seed); None when
    neither converges. A site filed under another's code can pull ``r`` so far off (RMS 780) that
    the other sites' fit from it does not converge, while their own IOD fits them cleanly."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.differential_correction import fit_orbit
    from cistrack.least_squares.trajectory import arc_states_and_stms

    def fitted(state):
        try:
            f = fit_orbit(ctx.dynamics, ctx.sensor, sub, state, r.epoch, options=opts)
        except (CistrackError, np.linalg.LinAlgError):
            return None
        return f if f.converged else None

    f = fitted(r.state)
    if f is not None:
        return f
    try:
        cloud = ctx.iod.estimate(sub, ctx.sensor, np.random.default_rng(ctx.seed))
        best = np.asarray((getattr(cloud, "meta", None) or {})["best_state"], dtype=float)
        start, _ = arc_states_and_stms(ctx.dynamics, best, float(cloud.epoch), np.array([r.epoch]))
    except (CistrackError, np.linalg.LinAlgError, KeyError):
        return None
    return fitted(start[0])


def _unclean(one, r, why: str) -> str:
    """The opening words of the message that ``r``, the ballistic fit of ``one`` that looks like a
    maneuver for ``why``, is not a clean fit: when the cap on rejections kept observations above the
    threshold, each alone in its night (:func:`_capped_alone`), those (probe I5: one outlier kept by
    the cap pulled a maneuver-free fit off its first night, which was reported as "an object that
    maneuvered")."""
    kept = _capped_alone(r)
    if not kept:
        return f"not a clean fit: it looks like an object that maneuvered ({why})"
    share = one.reject_fraction if one.reject_fraction is not None else one.choices.options.max_reject_fraction
    one_kept = kept == 1
    return (f"not a clean fit: {_count(kept, 'observation')} above the chi-square threshold "
            f"({r.rejection_threshold:.4g}) {'is' if one_kept else 'are'} kept because fit.max_reject_fraction "
            f"({share:g} applied) lets at most that share of the observations be rejected; {'it' if one_kept else 'they'} "
            f"may be what pulls the fit ({why})")


class _Outcome(NamedTuple):
    """One burn search of ``cistrack fit`` with its burn times checked (:func:`_measured`)."""

    found: Any                      # the ManeuverSearch
    fit: Any                        # the fit with the burns' time uncertainty carried (None when doubted early)
    burns: list                     # the burns with those covariances
    doubt: str                      # why they are not reported, in words ("" when they are)
    untimed: tuple = ()             # gaps (TU) whose burn time the time check could not settle
    searched: tuple = ()            # the search's burns before their times were checked (burn_key)


def _measured(ctx, one, say, first: _Outcome | None = None) -> _Outcome:
    """The burn search on ``one``'s ballistic fit, the burn times checked and their uncertainty
    carried into the fit (:func:`_completed`). Given the ``first`` search's outcome, the search
    again with its fits started where the orbits of a gap's two sides meet too, reusing the first's
    screened fits; when it finds the same burns the checks would repeat the first's: ``first``."""
    from cistrack.least_squares.burn_search import burn_fit_options, burn_key, search_maneuvers

    found = search_maneuvers(ctx.dynamics, ctx.sensor, ctx.measurements, one.result,
                             burn_fit_options(one.choices.options), say, again=None if first is None else first.found)
    searched = burn_key(found.burns)
    if first is not None and searched == first.searched:
        say("the same burns as the first search: its verdict stands")
        return first
    if not found.burns:
        return _Outcome(found, None, [], found.unsized or "no impulsive burn in the gaps between the observations "
                        "explains it")
    say(f"checking the time of the {_count(len(found.burns), 'burn')} found against every other time the arc allows "
        "(full fits in each night's gap)")
    found, doubt = _times_allowed(ctx, one, found, say)
    if doubt:
        return _Outcome(found, None, [], doubt, tuple(found.windows), searched)
    say("carrying the burn times' uncertainty into the orbit's covariance (two fits a burn)")
    fit, burns, failed = _completed(ctx, found)
    return _Outcome(found, fit, burns, failed or _burn_doubt(fit, burns), (), searched)


def _retried(ctx, one, first: _Outcome, say) -> _Outcome:
    """The search again with each burn started where the orbits of a gap's two sides meet
    (:func:`_measured` given ``first``), or ``first`` (the first search's) when that is not clean
    either or clashes with it (:func:`_clash`); the first's doubt then says so, and, when the
    second search found other burns, why they are not reported either (the first's words alone
    had been quoted for a retry doubted for another reason)."""
    again = _measured(ctx, one, say, first)
    if again is first:
        return first
    if again.doubt:
        return first._replace(doubt=f"{first.doubt}; searched again from where the orbits of a gap's two sides meet, "
                                    f"{again.doubt}")
    clash = _clash(first, again)
    return first._replace(doubt=f"{first.doubt}; {clash}") if clash else again


RIVAL_DV_M2 = 14.16
"""Mahalanobis^2 (3 dof, 99.7 %) beyond which another search's delta-v lies outside a burn's (:func:`_clash`)."""


def _clash(first: _Outcome, again: _Outcome) -> str:
    """Words when the ``again`` search's burns cannot replace the ``first``'s ("" when they can):
    a burn of ``again`` lies in a gap where the first search's time check found the cost with
    several minima (an unseen NRHO survey set's 1 m/s burn in a five-day gap: the first search
    timed it at 6.9 d and found 3.6 d cheaper; started where the sides meet, a 5.8 m/s burn at 2.9 d
    cheaper still was reported clean, its time 140 sigma off, while the truth's fit is cheaper
    again), or a burn of the first search fits within
    :data:`~cistrack.least_squares.burn_search.ALLOWED_COST` of ``again``'s fit and lies outside 3
    sigma of its burn in time or delta-v."""
    from cistrack.least_squares.burn_search import ALLOWED_COST
    from cistrack.least_squares.impulse_fit import capped_cost

    same = [b for b, w in zip(again.found.burns, again.found.windows) if w in first.untimed]
    if same:
        return (f"started where the sides of a gap meet, a burn of {same[0].magnitude_ms:.3g} m/s at "
                f"{_days(same[0].t):.3f} d fits, in the gap whose burn time the first search's check found "
                "undetermined: the cost has several minima there")
    f, a = first.found, again.found
    if not f.burns or capped_cost(f.result, f.prior) > capped_cost(a.result, a.prior) + ALLOWED_COST:
        return ""
    for b in f.burns:
        near = min(a.burns, key=lambda x: abs(x.t - b.t))
        e = np.asarray(b.delta_v_ms, dtype=float) - np.asarray(near.delta_v_ms, dtype=float)
        if abs(b.t - near.t) > 3.0 * near.t_sigma or e @ np.linalg.solve(near.covariance_ms2, e) > RIVAL_DV_M2:
            return (f"started where the sides of a gap meet, a burn of {near.magnitude_ms:.3g} m/s at "
                    f"{_days(near.t):.3f} d fits as well as one of {b.magnitude_ms:.3g} m/s at {_days(b.t):.3f} d "
                    f"(its cost within {ALLOWED_COST:g}) and lies outside that burn's 3 sigma: the arc does not "
                    "determine which")
    return ""


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _times_allowed(ctx, one, found, say):
    """:func:`~cistrack.least_squares.burn_search.times_allowed` on the search's arc."""
    from cistrack.least_squares.burn_search import burn_fit_options, times_allowed
    from cistrack.least_squares.impulse_fit import BurnArc

    opts = burn_fit_options(replace(one.choices.options, area_to_mass="solve" if one.result.parameter_names else "off"))
    return times_allowed(BurnArc(ctx.dynamics, ctx.sensor, ctx.measurements, opts, found.prior), found, say)


def _burn_doubt(fit, burns) -> str:
    """Why the fit with the ``burns`` the search kept is not reported as their measurement, in words
    ("" when it is): a burn whose magnitude is within :data:`MIN_BURN_SIGMAS` of its sigmas of none
    with fewer than two nights on one side (:func:`_one_night_side`), a burn time whose uncertainty was not measured, the fit still suspect
    (:func:`~cistrack.least_squares.burn_search.suspicion`), or more of its observations rejected
    than outliers explain (:func:`_rejects_too_many`)."""
    from cistrack.least_squares.burn_search import suspicion

    tried = "; ".join(_size_text(b) for b in burns)
    traded = [b for b in burns if not b.widened and _time_trade(b) > MAX_TIME_TRADE]
    if traded:
        return (f"the burn the search kept ({tried}) trades its size against its time (within one sigma of its "
                f"time the delta-v it needs changes by {max(map(_time_trade, traded)):.3g} times its size): the arc "
                "determines neither")
    vague = [b for k, b in enumerate(burns) if not _sized(fit, k, b)]
    if vague:  # a burn the arc cannot tell from none explains nothing (mis-identified tracklets at the arc's end)
        return (f"the burn the search kept ({tried}) is within {_least_sigmas(fit, vague[0]):g} sigma of none: the arc does not "
                "determine it (outliers, mis-identified observations or another object are as likely)")
    if any(b.dv_dt is None or not b.t_sigma > 0 for b in burns):
        return (f"the time of the burn the search kept ({tried}) has no measured uncertainty (its fits either side "
                "failed): its time and size are not determined")
    still = suspicion(fit) or _rejects_too_many(fit)
    if still:  # the burns do not explain what made the fit suspect: not reported as maneuvers
        return f"with the burns found ({tried}) {still}: they do not explain it (outliers, a bias or another object are as likely)"
    return ""


def _size_text(burn: BurnEstimate) -> str:
    """"N +- S m/s" for ``burn``, or, for a burn of any size
    (:func:`~cistrack.least_squares.burn_search.any_size`), those words with no figure."""
    from cistrack.least_squares.burn_search import any_size

    beyond = any_size(burn)
    return f"one of any size: {beyond}" if beyond else f"{burn.magnitude_ms:.3g} +- {burn.magnitude_sigma_ms:.3g} m/s"


MIN_TESTED_BURN_SIGMAS = 2.0
"""The smallest magnitude, in its sigmas, of a burn reported with two nights or more on each side
(:func:`_least_sigmas`). Without it unseen survey sets had been reported with 17 +- 170 m/s (the
truth after the burn at Mahalanobis^2 383), 0.9 +- 140 and 2.1 +- 2.0 m/s: the test against the fit
without a burn found one, but the arc measured nothing of it."""


def _least_sigmas(fit, burn: BurnEstimate) -> float:
    """The magnitude in sigmas a reported burn needs: :data:`MIN_BURN_SIGMAS` with fewer than two
    nights on a side of it (:func:`_one_night_side`), :data:`MIN_TESTED_BURN_SIGMAS` otherwise."""
    return MIN_BURN_SIGMAS if _one_night_side(fit, burn) else MIN_TESTED_BURN_SIGMAS


def _sized(fit, k: int, burn: BurnEstimate) -> bool:
    """Whether burn ``k``'s magnitude is far enough from none to report: at least
    :data:`MIN_BURN_SIGMAS` of its sigmas (:func:`_significance`), or, with two nights or more
    on each side, :data:`MIN_TESTED_BURN_SIGMAS` of them both there and in its size's own sigma
    (second order, ``magnitude_sigma_ms``: an unseen set's 2.1 +- 2.0 m/s was 2 first-order sigmas
    from none, its delta-v's spread across the burn's direction being what the size's sigma holds)."""
    sig = _significance(fit, k, burn)
    if sig >= MIN_BURN_SIGMAS:
        return True
    need = _least_sigmas(fit, burn)
    return bool(sig >= need and burn.magnitude_ms >= need * burn.magnitude_sigma_ms)


def _one_night_side(fit, burn: BurnEstimate) -> bool:
    """Whether the observations on one side of ``burn`` fall within fewer than
    :data:`~cistrack.least_squares.split_start.MIN_SIDE_NIGHTS` nights: a burn's time and delta-v
    fit any one tracklet (angles and rates), so only there can a mis-identified tracklet or another
    object pass for a burn. With two nights or more a side tests the burn: the test against the fit
    without it (a chi-square drop of 14,896 on a DRO's 1 m/s burn with two nights before it) says
    there was one, however wide its size's sigma (0.86 +- 0.32 m/s: the two nights leave one
    direction of the pre-burn orbit weak)."""
    from cistrack.least_squares.split_start import MIN_SIDE_NIGHTS, side_nights

    t = np.asarray(fit.residuals.times, dtype=float)
    return min(side_nights(t[t < burn.t]), side_nights(t[t > burn.t])) < MIN_SIDE_NIGHTS


def _size_words(fit, burns: list[BurnEstimate]) -> str:
    """"" when every burn's size is at least :data:`MIN_BURN_SIGMAS` sigma; else words saying which is not."""
    vague = [k for k, b in enumerate(burns) if not _significance(fit, k, b) >= MIN_BURN_SIGMAS]
    if not vague:
        return ""
    return ("; the size of burn " + ", ".join(str(k + 1) for k in vague) + f" is within {MIN_BURN_SIGMAS:g} sigma of "
            "none: the observations either side show a burn, not well how large (one direction of the orbit on "
            "the shorter side is weak)")


def _significance(fit, k: int, burn: BurnEstimate) -> float:
    """|dv| in sigmas of burn ``k``: at every time within 3 sigmas of its own
    (:func:`least_significance`) when its time's uncertainty is the linear term alone; in its whole
    covariance when that was widened to other times the arc allows (full fits there: the linear
    term, taken so far, describes nothing)."""
    if burn.widened:
        return burn.magnitude_ms / burn.magnitude_sigma_ms if burn.magnitude_sigma_ms > 0 else np.inf
    return least_significance(fit, k, burn)


def _time_trade(burn: BurnEstimate) -> float:
    """|g| sigma_t / |dv|: how much the delta-v a burn needs changes within one sigma of its time,
    in units of its size (0 when its time's uncertainty was not measured)."""
    if burn.dv_dt is None or not burn.magnitude_ms > 0:
        return 0.0
    return float(np.linalg.norm(burn.dv_dt) * burn.t_sigma / burn.magnitude_ms)


def least_significance(fit, k: int, burn: BurnEstimate) -> float:
    """The smallest |dv| / sigma(|dv|) of burn ``k`` over the burn times within 3 of its time
    sigmas, dv(t) = dv + g (t - t_b) (g = d dv / d t_b), sigma from the fit's covariance of dv at a
    fixed time (the burn's own covariance when the fit has none).

    The magnitude's sigma with the time's term mapped in linearly is the wrong measure: a burn
    time's uncertainty turns the delta-v more than it shrinks it (0.3 m/s along the velocity, timed
    +- 59 min, came out 0.278 +- 0.321 m/s, while every time within 3 sigma has |dv| at least 4 of
    its sigmas: the ballistic fit was excluded by 13 rejected observations)."""
    cov = _at_time_covariance(fit, k, burn)
    g = np.zeros(3) if burn.dv_dt is None else np.asarray(burn.dv_dt, dtype=float)
    steps = np.linspace(-3.0, 3.0, 61) * float(burn.t_sigma)
    dv = np.asarray(burn.delta_v_ms, dtype=float)[None, :] + steps[:, None] * g[None, :]
    size = np.linalg.norm(dv, axis=1)
    if not np.all(size > 0.0):
        return 0.0
    u = dv / size[:, None]
    sigma = np.sqrt(np.maximum(np.einsum("ki,ij,kj->k", u, cov, u), 0.0))
    return float(np.min(np.divide(size, sigma, out=np.full_like(size, np.inf), where=sigma > 0.0)))


def _at_time_covariance(fit, k: int, burn: BurnEstimate) -> np.ndarray:
    """(3, 3) (m/s)^2: burn ``k``'s delta-v covariance in ``fit`` (its time held fixed), else the
    burn's own."""
    block = _dv_block(fit, k)
    return np.asarray(burn.covariance_ms2, dtype=float) if block is None else block


def _dv_block(fit, k: int) -> np.ndarray | None:
    """(3, 3) (m/s)^2: the block of burn ``k``'s delta-v in ``fit``'s full covariance, found by its
    parameter names (None when the fit holds none)."""
    from cistrack.least_squares.impulse_fit import dv_names

    names = tuple(getattr(fit, "parameter_names", ()) or ())
    full = getattr(fit, "full_covariance", None)
    if full is None or not set(dv_names(k)) <= set(names):
        return None
    idx = [6 + names.index(n) for n in dv_names(k)]
    return np.asarray(full, dtype=float)[np.ix_(idx, idx)]


def _rejects_too_many(fit) -> str:
    """A fit with burns that still rejects more than :data:`~cistrack.least_squares.burn_search.BLOCK_SHARE`
    of its observations (and at least :data:`~cistrack.least_squares.burn_search.BLOCK_MIN`): the
    burns explain the arc only with its outliers; the rest should fit. Unseen survey sets (0.5 m/s)
    had their burn fitted a night early at 3.7 m/s rejecting 8 of 75, and 6.8 hours early (21
    sigma) rejecting 4 of 50, both called clean; fits with the right burn rejected 0-3 % of theirs."""
    from cistrack.least_squares.burn_search import BLOCK_MIN, BLOCK_SHARE

    rejected = np.asarray(fit.residuals.rejected, dtype=bool)
    n = int(rejected.sum())
    if n >= max(BLOCK_MIN, BLOCK_SHARE * rejected.size):
        return f"it still rejects {n} of {rejected.size} observations ({100.0 * n / rejected.size:.0f} %)"
    return ""


def _completed(ctx, found):
    """(fit, burns, "") of :func:`_after_burns`, or (None, [], why) when its fits cannot be made (a
    trajectory with the burns that meets the Moon has no transition matrix beyond the impact: a
    two-burn survey set had ended the whole fit there, with no fit.json)."""
    from cistrack.errors import PropagationError
    from cistrack.least_squares.errors import FitError

    try:
        return (*_after_burns(ctx, found), "")
    except (FitError, PropagationError) as exc:
        return None, [], f"the fit with the burns found cannot be completed ({exc})"


def _after_burns(ctx, found):
    """(fit, burns): the search's fit, refitted with its state at the last observation when its
    epoch lies before a burn (so that predictions forward of the epoch fly no burn), and the burns
    with the covariances of that fit (the burn times' uncertainty kept)."""
    from cistrack.least_squares.impulse_fit import BurnArc, fit_impulses
    from cistrack.least_squares.trajectory import arc_states

    fit = found.result
    t_last = float(np.max(ctx.measurements.times))
    if fit.epoch >= max(b.t for b in found.burns):
        arc = BurnArc(ctx.dynamics, ctx.sensor, ctx.measurements, fit_options(fit), found.prior)
        return _with_burn_times(arc, fit, found.burns, found.windows), found.burns
    x = arc_states(found.dynamics, fit.state, fit.epoch, np.array([t_last]))[0]
    arc = BurnArc(ctx.dynamics, ctx.sensor, ctx.measurements, fit_options(fit))
    again = fit_impulses(arc, x, t_last, [b.t for b in found.burns])
    burns = [replace(b, covariance_ms2=b.covariance_ms2 + (n.covariance_ms2 - _plain(found, k)))
             for k, (b, n) in enumerate(zip(found.burns, again.burns))]
    return _with_burn_times(arc, again.fit, burns, found.windows), burns


TIME_POINT = float(np.sqrt(3.0))
"""The burn time's two sigma points lie this many of its sigmas either side of it (with the
middle one, the three-point unscented rule of a Gaussian: exact for states quadratic in the time)."""


def _with_burn_times(arc, fit, burns, windows):
    """``fit`` (its epoch after the burns) with the burn times' uncertainty in its state covariance.

    The fit holds each burn's time t_b fixed. Refitted with that burn at another time t (the other
    burns kept where they are), its state at the epoch is x(t). With t ~ N(t_b, t_sigma^2) the
    spread of x(t) about the fit's state is E[(x(t) - x(t_b))(x(t) - x(t_b))^T], taken by the
    three-point unscented rule (:data:`TIME_POINT`): (d+ d+^T + d- d-^T) / 6 with
    d = x(t_b +- sqrt(3) t_sigma) - x(t_b), added per burn; a side whose point falls outside the
    burn's gap (``windows``) is stood for by the other (:func:`_time_points`).
    Full refits, not a derivative with the pre-burn orbit and delta-v held: when the time moves the
    fit moves both, and on unseen survey sets that derivative pointed elsewhere (the truth at
    Mahalanobis^2 120 and 72 after burns fitted with their right delta-v; 6.6 and 4.5 with this)."""
    extra = np.zeros((6, 6))
    for k, (b, window) in enumerate(zip(burns, windows)):
        if b.t_sigma > 0:
            extra += _time_spread(arc, fit, burns, k, window, b.t_sigma)
        if b.reach is not None:
            extra += _reach_spread(arc, fit, burns, k)
    return _widened(fit, extra) if extra.any() else fit


def _time_spread(arc, fit, burns, k: int, window: tuple[float, float], t_sigma: float) -> np.ndarray:
    """(6, 6): the unscented second moment of the state at ``fit``'s epoch about its own over burn
    ``k``'s time (:func:`_with_burn_times`); one side's point stands for both when the other's
    refit cannot be made (a time that flies into the Moon), and a FitError is raised when neither can."""
    from cistrack.errors import PropagationError
    from cistrack.least_squares.errors import FitError
    from cistrack.least_squares.impulse_fit import refit_moved

    lo, hi = window
    moved = []
    for t in _time_points(burns[k].t, TIME_POINT * t_sigma, lo, hi):
        try:
            x = refit_moved(arc, fit, burns, k, t).fit.state
        except (FitError, PropagationError):
            continue
        d = np.asarray(x, dtype=float) - np.asarray(fit.state, dtype=float)
        moved.append(np.outer(d, d))
    if not moved:
        raise FitError("the fits with the burn moved by its time's uncertainty cannot be made: "
                       "that uncertainty cannot be carried into the orbit")
    return sum(moved) / (3.0 * len(moved))


def _reach_spread(arc, fit, burns, k: int) -> np.ndarray:
    """(6, 6): d d^T / m^2, d the state at ``fit``'s epoch of the refit with burn ``k`` at the other
    time the arc allows that set its widened sigma, m sigmas away (``reach``), minus ``fit``'s
    (zero when that refit cannot be made), as the burn's delta-v covariance takes that time's
    (:func:`~cistrack.least_squares.burn_search.times_allowed`). The sigma points alone lie between
    the two times, where the cost can rise between two minima: a survey set's 0.3 m/s burn allowed
    at 3.37 d and at 8.82 d (6.8 more in cost; 50-60 more at 5-6.3 d) had its orbit's spread taken
    at 6.99 d, and the truth (9.23 d) lay at Mahalanobis^2 104."""
    from cistrack.errors import PropagationError
    from cistrack.least_squares.errors import FitError
    from cistrack.least_squares.impulse_fit import refit_moved

    t, m = burns[k].reach
    try:
        x = refit_moved(arc, fit, burns, k, t).fit.state
    except (FitError, PropagationError):
        return np.zeros((6, 6))
    d = np.asarray(x, dtype=float) - np.asarray(fit.state, dtype=float)
    return np.outer(d, d) / m ** 2


def _time_points(tb: float, step: float, lo: float, hi: float) -> list[float]:
    """The burn time's sigma points (TU) ``tb`` +- ``step`` that lie inside its gap [``lo``, ``hi``];
    when one lies beyond an edge, the other alone (it stands for both), and when both do, both
    clipped to the gap. A point clipped to the edge measures a smaller step than the rule takes:
    a survey set's 0.3 m/s burn timed 3.368 +- 2.09 d, 0.18 d after its gap's start, had its
    earlier point clipped there, the spread of its orbit halved, and the truth (9.23 d, its time z
    -2.8) at Mahalanobis^2 123 (104 with the later point alone)."""
    inside = [t for t in (tb - step, tb + step) if lo <= t <= hi]
    return inside or [min(max(t, lo), hi) for t in (tb - step, tb + step)]


def _plain(found, k: int) -> np.ndarray:
    """Burn ``k``'s covariance from the search's fit itself (without the burn time's part)."""
    return _dv_block(found.result, k)


def fit_options(fit):
    """FitOptions for a refit of ``fit``: the area-to-mass ratio estimated when ``fit`` estimated it."""
    from cistrack.least_squares.burn_search import burn_fit_options
    from cistrack.least_squares.options import FitOptions

    return burn_fit_options(FitOptions(area_to_mass="solve" if "area_to_mass_m2_kg" in fit.parameter_names else "off"))


def _without_burns(fit):
    """``fit`` with the burns' delta-v taken out of its parameters (the state's covariance keeps
    their uncertainty: it is the marginal block of the joint one)."""
    names = list(fit.parameter_names)
    keep = [i for i, n in enumerate(names) if not n.startswith("delta_v_")]
    if len(keep) == len(names):
        return fit
    full = np.asarray(fit.full_covariance, dtype=float)
    idx = list(range(6)) + [6 + i for i in keep]
    return replace(fit, parameter_names=tuple(names[i] for i in keep),
                   parameters=np.asarray(fit.parameters, dtype=float)[keep],
                   full_covariance=full[np.ix_(idx, idx)] if keep else None)
