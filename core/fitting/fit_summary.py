"""The printed summary of a fit, for a person: what ``cistrack fit`` prints per object and what
:meth:`cistrack.fitting.from_observations.ObjectFit.report` returns.

For a converged fit: the verdict with how well the orbit is determined, the results folder, the
filter run's outcome, the least squares' epoch, observations used and rejected, weighted RMS and
chi-square, the assumed and estimated noise per component, the 1-sigma position and velocity at
the fit epoch, the line of variations, the earlier arcs' residual ladder, the orbit's events and
every note and warning. For observations that determine no orbit (one lone tracklet): why, in
words, with the tracklet's motion and admissible region.
"""
from __future__ import annotations

import math

import numpy as np

from cistrack.errors import clipped

__all__ = ["summary_lines", "short_lines"]


def _arcs_and_events(one) -> list[str]:
    """The residual ladder of the earlier arcs and the orbit's events (impacts, closest approaches)."""
    lines: list[str] = []
    arcs = getattr(one, "arcs", None)
    if arcs is not None and arcs.ladder:
        from cistrack.fitting.arc_fit import ladder_verdicts
        from cistrack.fitting.residual_ladder import ladder_table

        lines.append("  earlier arcs against this fit (residual ladder):")
        lines += ["    " + ln for ln in ladder_table(arcs.ladder, one.scenario.epoch).splitlines()]
        lines.append("  " + ladder_verdicts(arcs.ladder))
    if one.ok and getattr(one, "events", None) is not None:
        from cistrack.least_squares.events import event_lines

        lines += event_lines(one.events)
    if one.ok and getattr(one, "burn_sensitivity", None):
        lines.append(_hidden_burn_line(one.burn_sensitivity[-1], one.scenario.epoch))
        lines += _earlier_gap_line(one.burn_sensitivity[:-1], one.scenario.epoch)
    return lines


HIDDEN_ANY_SIZE_MS = 100.0
"""A hidden burn larger than this (m/s) is said to be of any size: beyond it the linear figure
means little (the fit absorbs such burns by rejecting the observations after them)."""


def _utc(epoch, t: float) -> str:
    from cistrack import units

    return units.format_utc(units.tu_to_utc(epoch, t))[:16]


def _size_words(x: float) -> str:
    """A hidden burn's size in words: "of any size" beyond :data:`HIDDEN_ANY_SIZE_MS`, else "of N m/s"."""
    if not x <= HIDDEN_ANY_SIZE_MS:
        return "of any size"
    return f"of {x:.0f} m/s" if x >= 10.0 else f"of {x:.2g} m/s"


def _hidden_burn_line(gap, epoch) -> str:
    """What a burn in the last gap between observing sessions could do unseen."""
    x = gap.largest_hidden_ms
    where = f"between {_utc(epoch, gap.start)} and {_utc(epoch, gap.end)} (the last gap between sessions)"
    if not x <= HIDDEN_ANY_SIZE_MS:
        return (f"  maneuvers: a burn of any size {where} could go unseen in these observations; the orbit after it "
                "assumes none (fit.json burn_sensitivity: every gap)")
    return (f"  maneuvers: a burn {_size_words(x)} {where}, at its worst time and direction, would not show in these "
            "observations (nor some larger ones, whose observations the fit would reject); the orbit after it assumes "
            "none (fit.json burn_sensitivity: every gap)")


def _earlier_gap_line(gaps, epoch) -> list[str]:
    """The earlier gap (before the last) that hides the largest burn, as one line ([] for none): a
    survey fit left "converged" by a 0.3 m/s burn in a six-day gap had named only the last gap, the
    burn's gap only in fit.json."""
    if not gaps:
        return []
    blind = [g for g in gaps if not g.largest_hidden_ms <= HIDDEN_ANY_SIZE_MS]
    if len(blind) > 1:
        return [f"    before it, {len(blind)} of the {len(gaps)} earlier gaps could hide a burn of any size too (the first "
                f"between {_utc(epoch, blind[0].start)} and {_utc(epoch, blind[0].end)})"]
    worst = blind[0] if blind else max(gaps, key=lambda g: g.largest_hidden_ms)
    return [f"    before it, the gap between {_utc(epoch, worst.start)} and {_utc(epoch, worst.end)} hides the largest: "
            f"a burn {_size_words(worst.largest_hidden_ms)} there, at its worst time and direction, would not show "
            "either"]


def _wrapped(lines: list[str], width: int = 118) -> list[str]:
    """``lines`` folded to ``width`` columns, continuations indented two more spaces."""
    import textwrap

    out: list[str] = []
    for line in lines:
        lead = " " * (len(line) - len(line.lstrip(" ")))
        out += textwrap.wrap(line, width, subsequent_indent=lead + "  ", break_on_hyphens=False) or [line]
    return out


def _motion_line(sky: dict) -> str:
    """The tracklet's motion on the sky, or that one time measures none."""
    if sky.get("angles") == "azel":
        return ("  motion: not given for azimuth/elevation (their rates mix the Earth's rotation with the object's "
                "own motion)")
    if sky["rate_arcsec_min"] is None:
        return (f"  motion: not measured ({'one exposure' if sky['n_observations'] == 1 else 'every exposure at one time'}"
                "; a tracklet's motion needs two times at least)")
    return (f"  motion: RA cos(Dec) {sky['ra_cos_dec_rate_arcsec_min']:+.3g} \"/min, Dec {sky['dec_rate_arcsec_min']:+.3g} "
            f"\"/min ({sky['rate_arcsec_min']:.3g} \"/min = {sky['rate_deg_day']:.3g} deg/day, position angle "
            f"{sky['position_angle_deg']:.1f} deg)")


def _place(sky: dict) -> str:
    """The tracklet's two angles at its mean time, named as measured (RA/Dec or azimuth/elevation)."""
    if sky.get("angles") == "azel":
        return f"azimuth {sky['azimuth_deg']:.4f} deg, elevation {sky['elevation_deg']:+.4f} deg"
    return f"RA {sky['ra_deg']:.4f} deg, Dec {sky['dec_deg']:+.4f} deg"


def _undetermined_lines(one) -> list[str]:
    """The summary of observations that determine no orbit (one lone tracklet): why, where the
    tracklet is and how it moves on the sky, and the admissible region's ranges."""
    u = one.undetermined
    sky, region = u["tracklet"], u["admissible_region"]
    lines = [f"fit {clipped(one.designation)}: UNDETERMINED: one tracklet does not determine an orbit",
             f"  results in {one.directory}",
             f"  tracklet: {sky['n_observations']} observations from {sky['first_utc'][:19]}Z to "
             f"{sky['last_utc'][11:19]}Z ({sky['span_minutes']:.0f} min), site {sky['site'] or '(the sensor)'}; "
             f"{_place(sky)} at its mean time",
             _motion_line(sky)]
    if "range_km" in region:
        lo, hi = region["range_km"]
        rlo, rhi = region["range_rate_kms"]
        lines.append(f"  admissible region (geocentric C3 <= {region['max_c3_km2_s2']:g} km^2/s^2): range {lo:,.0f} to "
                     f"{hi:,.0f} km, range rate {rlo:+.3g} to {rhi:+.3g} km/s: the orbit may lie anywhere in it")
    else:
        lines.append(f"  admissible region: {region.get('why_none', 'not computed')}")
    lines.append("  two angles and their rates leave the range and the range rate free: observe the object again on "
                 "another night (or from another site) and fit all the observations together")
    lines.append("  no orbit, nothing to export (exit status 3); see docs/real-data.md, 'When a fit fails'")
    return _wrapped(lines)


def _header_lines(one) -> list[str]:
    """The verdict (with how well the orbit is determined), the results folder, the filter run."""
    det = getattr(one, "determination", None)
    if det is None or not one.ok:
        lines = [f"fit {clipped(one.designation)}: " + ("converged" if one.ok else "FAILED")]
    else:  # never a bare "converged": how well the orbit is determined, and why, on the next line
        kind, _, why = det.sentence.partition(": ")
        lines = [f"fit {clipped(one.designation)}: converged; {kind}", f"  {why}"]
    lines.append(f"  results in {one.directory}")
    if one.run is not None:
        s = one.run.summary
        lines.append(f"  filter {one.scenario.components['filter'].name} after IOD "
                     f"{one.scenario.components['iod'].name}: {s.status}"
                     + (f" ({s.failure})" if s.failure else "")
                     + (f"; verdict {s.verdict.kind}" if getattr(s.verdict, "kind", None) else ""))
    if one.failure and one.result is None:  # a fit's own failure is among its notes, with the warning
        lines.append(f"  error: {one.failure}")
    return lines


def summary_lines(one) -> list[str]:
    """The printed summary of one :class:`~cistrack.fitting.from_observations.ObjectFit`."""
    from cistrack import units
    from cistrack.fitting.fit_record import area_to_mass_summary
    from cistrack.fitting.stated_noise import too_small_words
    from cistrack.least_squares.observability import condition_text

    if getattr(one, "undetermined", None):
        return _undetermined_lines(one)
    lines = _header_lines(one)
    r = one.result
    if r is None:
        lines.append("  no orbit: see docs/real-data.md, 'When a fit fails'")
        return _wrapped(lines)
    too_small = too_small_words(r.residuals)
    if too_small:  # first: every verdict below (a maneuver's included) is drawn with these weights
        lines.insert(1, f"  warning: {too_small}")
    ms = one.run.context.measurements
    epoch = units.format_utc(units.tu_to_utc(one.scenario.epoch, r.epoch))[:19] + "Z"
    if one.start:
        lines.append(f"  least squares restarted from {one.start}")
    lines.append(f"  least squares at {epoch} ({one.choices.epoch} observation): {len(ms)} observations, "
                 f"{r.n_used} used, {r.n_rejected} rejected; weighted RMS {r.rms:.3f}, chi-square {r.chi2:.1f} "
                 f"for {2 * r.n_used - 6 - len(r.parameter_names)} degrees of freedom")
    lines += _noise_lines(ms, r)
    lines += rejected_site_lines(r.residuals)
    sig = r.sigmas_km
    lines.append("  1-sigma at the fit epoch (synodic): position " + " / ".join(f"{v:.3g}" for v in sig[:3])
                 + " km; velocity " + " / ".join(f"{1e5 * v:.3g}" for v in sig[3:]) + " cm/s; "
                 + condition_text(r.condition_number))
    lines += area_to_mass_summary(r)
    if r.noise_scale > 1.0:
        lines.append(f"  the exported covariance is this one times the noise scale squared ({r.noise_scale ** 2:.3g}): "
                     "the residuals exceed the stated noise")
    for m in r.messages[1:]:
        lines.append(f"  note: {m}")
    if one.lov:
        lines += _lov_lines(one.lov, r)
    lines += _arcs_and_events(one)
    if r.unobservable:
        lines.append("  warning: part of the orbit is poorly determined by this arc (see the note above)")
    if not r.converged:
        what = _not_converged_words(r)
        lines.append(f"  warning: {what}; the orbit is not exported without --force "
                     "(docs/real-data.md, 'When a fit fails')")
    if r.noise_scale > 1.5 and not too_small:
        lines.append(f"  warning: the residuals are {r.noise_scale:.2g} times the assumed noise: check the weights "
                     "(--set measurements.reader.sigma_arcsec=..., with --set measurements.reader.sigma_from_file=false "
                     "for files that state their own rmsRA/rmsDec) or the data")
    lines += _too_large_lines(r)
    return _wrapped(lines)


TOO_LARGE_QUANTILE = 1e-4
"""A fit's chi-square below this quantile of its chi-square distribution says that the stated
uncertainties are too large (a consistent fit falls there once in 10^4)."""


def _too_large_lines(r) -> list[str]:
    """A warning when the fit ``r``'s chi-square lies below :data:`TOO_LARGE_QUANTILE` of its
    distribution (10 degrees of freedom or more): the residuals are far below the stated noise, the
    stated uncertainties too large and the covariance with them too wide (probe N: rmsRA = rmsDec =
    17" on 0.85" data gave chi-square 0.1 for 38 degrees of freedom and no word)."""
    from cistrack.numerics.special_functions import chi2_ppf

    dof = 2 * r.n_used - 6 - len(r.parameter_names)
    if dof < 10 or not r.chi2 < chi2_ppf(TOO_LARGE_QUANTILE, dof):
        return []
    return [f"  warning: the residuals are {r.rms:.2g} times the stated noise (chi-square {r.chi2:.3g} for {dof} "
            f"degrees of freedom, below the {chi2_ppf(TOO_LARGE_QUANTILE, dof):.3g} a consistent fit exceeds but once "
            "in 10^4): the stated uncertainties look too large, and the covariance with them too wide; check the "
            "weights (--set measurements.reader.sigma_arcsec=..., with --set measurements.reader.sigma_from_file=false "
            "for files that state their own rmsRA/rmsDec)"]


def _not_converged_words(r) -> str:
    """Why the fit ``r`` is not reported as converged: its least squares did not converge (its
    first message says so) and/or a later verdict found it not clean (a message "not a ...");
    never "the least squares converged" of one that did not (probe M8)."""
    unclean = any(str(m).startswith("not a ") for m in r.messages)
    ls_converged = bool(r.messages) and str(r.messages[0]).startswith("converged")
    if not unclean:
        return "the least squares did not converge"
    if ls_converged:
        return "the least squares converged, but the fit is not a clean one (the note above)"
    return "the least squares did not converge, and the fit is not a clean one (the note above)"


def rejected_site_lines(table) -> list[str]:
    """A warning per site all of whose observations (3 or more) the fit ``table`` (a
    :class:`~cistrack.least_squares.residual_table.ResidualTable`) rejected: a whole site set aside
    is no outlier (probe J6: 711's 15 observations, 37 % of the data, stating 1.1 mas, had been
    rejected without a word under "well determined"). It says how far their residuals are from
    their stated uncertainties, and when those are far smaller than the other sites', so."""
    if table is None or len(table) == 0:
        return []
    sites = np.asarray(table.sites).astype(str)
    lines = []
    for site in dict.fromkeys(sites.tolist()):
        mine = sites == site
        n = int(mine.sum())
        if not site or n < 3 or not np.all(table.rejected[mine]):
            continue
        size = float(np.nanmedian(np.abs(table.normalised[mine])))
        times = f"{size:,.0f}" if size >= 100 else f"{size:.3g}"
        lines.append(f"  warning: all {n} observations of site {site} ({100.0 * n / len(table):.0f} % of the data) "
                     f"were rejected: their residuals are a median {times} times their stated uncertainties"
                     + _stated_too_small(table, mine, site))
    return lines


def _stated_too_small(table, mine: np.ndarray, site: str) -> str:
    """", which look far too small: ..." when the angle uncertainties the rows ``mine`` state are
    under a tenth of the other sites' (medians, arcsec); "" otherwise."""
    angles = [j for j, unit in enumerate(table.units) if unit == "arcsec"]
    if not angles or not np.any(~mine):
        return ""
    with np.errstate(divide="ignore", invalid="ignore"):
        stated = np.abs(table.o_c[:, angles] / table.normalised[:, angles])
    own, others = float(np.nanmedian(stated[mine])), float(np.nanmedian(stated[~mine]))
    if not own < others / 10:
        return ""
    return (f"; they state {own:.2g}\" against {others:.2g}\" at the other sites, which looks far too small: check "
            f"{site}'s stated uncertainties (rmsRA/rmsDec)")


def _noise_lines(ms, r) -> list[str]:
    """Per measured quantity: the assumed noise, the noise estimated from the residuals (the assumed
    one times the noise scale; in words when the scale is undetermined), the post-fit RMS (km or arcsec)."""
    from cistrack.fitting.fit_record import noise_summary
    from cistrack.least_squares.result import noise_scale_text

    lines = []
    for name, v in noise_summary(ms, r).items():
        unit = "km" if name.endswith("_km") else "arcsec"
        label = name.rsplit("_", 1)[0].replace("ra_cos_dec", "RA cos(Dec)").replace("declination", "Dec")
        estimated = (f"estimated {v['estimated']:.3g} {unit} (noise scale {r.noise_scale:.3f})"
                     if math.isfinite(r.noise_scale) else f"not estimated: the noise scale is {noise_scale_text(r.noise_scale)}")
        lines.append(f"  {label}: assumed noise {v['assumed']:.3g} {unit}, {estimated}, "
                     f"post-fit RMS {v['post_fit_rms']:.3g} {unit}")
    return lines


def _lov_lines(points: list, r) -> list[str]:
    """The summary's lines on the line of variations ``points`` of fit ``r``."""
    from cistrack.least_squares.line_of_variations import line_summary

    lv = line_summary(points, r)
    lo, hi = lv["sigma_range"]
    if not lv["followed"]:
        return [f"  line of variations: followed only from {lo:g} to {hi:g} sigma ({len(points)} point(s), lov.csv): "
                "the fits beyond its first points did not converge, so it checks nothing",
                "  warning: the covariance is unchecked and may understate the uncertainty, and the 1-sigma, the "
                "horizon and the sky predictions drawn from it with it; observe again sooner"]
    out = [f"  line of variations {lo:g} to {hi:g} sigma ({len(points)} points, lov.csv): leaves the "
           f"straight line by at most {lv['max_departure_sigma']:.3g} sigma ({lv['max_departure_km']:.3g} km), "
           f"chi-square within {lv['max_chi2_excess']:.3g} of sigma^2"]
    if not lv["linear"]:
        out += _reach_lines(lv)
        out.append("  warning: the solutions bend away from the covariance's ellipsoid: the covariance "
                   "understates the uncertainty, and the 1-sigma and the horizon drawn from it with it (cistrack "
                   "predict widens its ellipses to hold the line); sample the line (lov.csv, "
                   "cistrack.least_squares.line_of_variations), or observe again sooner")
    return out


def _reach_lines(lv: dict) -> list[str]:
    """Where the orbits the data allow lie along the line (its other minima, its 3-sigma reach)."""
    out = []
    for m in lv["minima"][1:]:
        out.append(f"  another solution along the line at {m['sigma']:+g} sigma: chi-square {m['delta_chi2']:.3g} higher, "
                   f"{m['offset_km']:,.0f} km from the fit at the epoch" + (" (the line was cut there: the minimum may lie "
                                                                             "beyond)" if m["at_end"] else ""))
    reach = lv["reach"]
    lo, hi = reach["sigma_range"]
    out.append(f"  within 3 sigma (chi-square within 9 of the lowest) the line runs from {lo:+g} to {hi:+g} sigma: orbits "
               f"up to {reach['max_offset_km']:,.0f} km from the fit at the epoch"
               + (", and on beyond the line's end" if reach["open"] else ""))
    return out


def _outcome(one) -> str:
    """One phrase: converged (and how well determined), undetermined, or failed (and why, shortened)."""
    if getattr(one, "undetermined", None):
        return "UNDETERMINED: one tracklet does not determine an orbit"
    det = getattr(one, "determination", None)
    if one.ok:
        return "converged" + (f"; {det.sentence.partition(': ')[0]}" if det is not None else "")
    why = one.failure or (one.result.messages[0] if one.result is not None and one.result.messages else "")
    why = why if len(why) <= 160 else why[:157] + "..."
    return "FAILED" + (f": {why}" if why else "")


def short_lines(one) -> list[str]:
    """The short form of an :class:`~cistrack.fitting.from_observations.ObjectFit` (its ``repr``): the
    object and outcome, the method, the observations used and rejected with the weighted RMS, the
    fit epoch and the results folder."""
    from cistrack import units

    lines = [f"<ObjectFit {clipped(one.designation)}: {_outcome(one)}"]
    scen = one.scenario
    if scen is not None:
        iod = (one.seeding or {}).get("method") or scen.components["iod"].name
        lines.append(f"  method: IOD '{iod}', filter '{scen.components['filter'].name}', least squares"
                     + (f" at the {one.choices.epoch} observation" if one.result is not None else " (not made)"))
    r = one.result
    if r is not None:
        n = len(one.run.context.measurements) if one.run is not None else r.n_used + r.n_rejected
        epoch = units.format_utc(units.tu_to_utc(scen.epoch, r.epoch))[:19] + "Z"
        lines.append(f"  observations: {n}, {r.n_used} used, {r.n_rejected} rejected; weighted RMS {r.rms:.3f}")
        lines.append(f"  epoch: {epoch}")
    lines.append(f"  results in {one.directory} (.report() for the full summary)>")
    return lines
