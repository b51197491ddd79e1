"""What ``cistrack fit`` adds to a converged fit: which arc it fitted and how the others fare
against it (:mod:`.arcs`, :mod:`.arc_fit`, :mod:`.residual_ladder`), how well the orbit is
determined, in words (:mod:`.determination`), and the orbit's impacts and closest approaches
(:mod:`cistrack.least_squares.events`).

An object's observations are split into arcs by long gaps (``fit.arc_gap_days``); by default
(``fit.arcs = "latest"``) the workflow fits the latest. When that fit explains its arc (it
rejects at most :data:`EXPLAINED_REJECTED` of it), the arc is one orbit. When it explains it only
by rejecting more, the workflow tests whether the earlier groups of the arc link to its latest
(``fit.link_gap_days``), and, when a link is broken, fits again on the groups that link, so that
the residuals, plots and exports all describe the observations the orbit explains. (Testing the
links of an arc that one orbit already explains would judge them by the fit of the latest group
alone, whose prediction is too weakly determined on survey cadences: a few tracklets.) The arcs
left out are reported as a residual ladder (how far the fit's prediction misses each).
"""
from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.astro.site_network import build_site_network
from cistrack.fitting.arc_fit import ArcFit, latest_arc_fit
from cistrack.fitting.arcs import arc_sets, in_time_base
from cistrack.fitting.determination import determination, is_lone_tracklet
from cistrack.fitting.observation_input import READ_EPOCH, ObjectObservations
from cistrack.fitting.residual_ladder import fitted_dynamics
from cistrack.least_squares.burn_sensitivity import burn_sensitivity
from cistrack.least_squares.events import fit_events
from cistrack.plugin.registry import Registry

__all__ = ["arcs_to_fit", "latest_determined_arc", "before_arc", "left_out_note", "earlier_arcs_text",
           "first_clause", "arc_report", "kept_observations", "add_findings", "EXPLAINED_REJECTED"]

EXPLAINED_REJECTED = 0.1
"""A fit that rejects at most this share of its arc's observations explains the arc: its links
are not tested (the least squares' own rejection of gross outliers stays well below it)."""


def arcs_to_fit(obs: ObjectObservations, choice: str, arc_gap_days: float) -> list[ObjectObservations]:
    """The observation sets to fit for ``fit.arcs = choice`` ("latest": one, "each": every arc,
    oldest first, "all": everything at once), each as an :class:`ObjectObservations`."""
    return [dataclasses.replace(obs, measurements=ms) for ms in arc_sets(obs.measurements, choice, arc_gap_days)]


def latest_determined_arc(obs: ObjectObservations, arc_gap_days: float) -> tuple[ObjectObservations, ObjectObservations, str]:
    """What ``fit.arcs = "latest"`` fits: the latest long-gap arc that is more than one lone
    tracklet (:func:`cistrack.fitting.determination.is_lone_tracklet`: it alone determines no
    orbit). Returns (the observations up to that arc's end, the arc, a note on the lone tracklets
    after it that are not fitted, "" when there are none). When every arc is a lone tracklet, the
    latest is the arc (the fit then says what a lone tracklet gives)."""
    arcs = arcs_to_fit(obs, "each", arc_gap_days)
    determined = [i for i, a in enumerate(arcs) if not is_lone_tracklet(a.measurements)]
    if not determined or determined[-1] == len(arcs) - 1:
        return obs, arcs[-1], ""
    k = determined[-1]
    times = obs.measurements.times
    end = float(arcs[k].measurements.times[-1])
    upto = dataclasses.replace(obs, measurements=obs.measurements.subset(times <= end))
    later = [a.measurements for a in arcs[k + 1:]]
    epoch = units.parse_utc(READ_EPOCH)
    first = units.tu_to_utc(epoch, float(later[0].times[0]))
    n = sum(len(ms) for ms in later)
    note = (f"{n} observation(s) after the fitted arc, in {len(later)} lone tracklet(s) more than "
            f"{arc_gap_days:g} days later (the first from site {later[0].site_at(0)} on {first:%Y-%m-%d}, "
            f"{units.tu_to_days(float(later[0].times[0]) - end):.1f} days after the arc), are not fitted: a lone "
            "tracklet determines no orbit on its own (fit.arcs=all fits one orbit over every observation)")
    return upto, arcs[k], note


def before_arc(obs: ObjectObservations, arc: ObjectObservations) -> ObjectObservations | None:
    """``obs`` without ``arc`` and what follows it (the earlier arcs), or None when nothing is
    before it."""
    start = float(arc.measurements.times[0])
    keep = np.asarray(obs.measurements.times, dtype=float) < start
    return dataclasses.replace(obs, measurements=obs.measurements.subset(keep)) if keep.any() else None


def first_clause(text: str) -> str:
    """``text`` up to its first "; " outside parentheses (a failure without its advice)."""
    depth = 0
    for i, c in enumerate(text):
        depth += (c == "(") - (c == ")")
        if depth == 0 and text.startswith("; ", i):
            return text[:i]
    return text


def left_out_note(left: ObjectObservations, fitted: ObjectObservations, why: str) -> str:
    """The note of a fit that fell back to the earlier arc ``fitted`` because the fit of the later
    observations ``left`` failed before its first step (``why``: that failure): how many, from
    which sites and dates, how long after the fitted arc, why (without the failure's advice, which
    would fit an orbit to them alone), and the way to fit each arc on its own."""
    ms, epoch = left.measurements, units.parse_utc(READ_EPOCH)
    first, last = (units.tu_to_utc(epoch, float(ms.times[i])) for i in (0, -1))
    after = units.tu_to_days(float(ms.times[0]) - float(fitted.measurements.times[-1]))
    sites = ", ".join(sorted({ms.site_at(i) for i in range(len(ms))} - {""})) or "the sensor's own site"
    reason = first_clause(why.removeprefix("the filter run failed before its first step: "))
    return (f"{len(ms)} later observation(s) ({sites}, {first:%Y-%m-%d} to {last:%Y-%m-%d}, {float(after):.1f} days "
            f"after the fitted arc) are not fitted: no orbit determination starts from them ({reason}); the fit "
            "is of the latest arc before them that can be fitted (later observations that no orbit fits may be "
            "another object's under this designation: --set fit.arcs=each fits each arc on its own)")


def earlier_arcs_text(obs: ObjectObservations, arc: ObjectObservations, arc_gap_days: float) -> str:
    """The arcs of ``obs`` before ``arc`` in words (count, observations, dates) with the way to fit
    each on its own; "" when there are none."""
    before = before_arc(obs, arc)
    if before is None:
        return ""
    arcs = arcs_to_fit(before, "each", arc_gap_days)
    epoch = units.parse_utc(READ_EPOCH)
    told = ", ".join(f"{len(a.measurements)} observation(s) from "
                     f"{units.tu_to_utc(epoch, float(a.measurements.times[0])):%Y-%m-%d} to "
                     f"{units.tu_to_utc(epoch, float(a.measurements.times[-1])):%Y-%m-%d}" for a in arcs)
    return (f"the object's {len(arcs)} earlier arc(s) ({told}) are not fitted with it, and none of them could be "
            "fitted in its place: --set fit.arcs=each fits each arc on its own")


def _everything(one, obs: ObjectObservations, registry: Registry):
    """All of the object's observations in the fit's time base, and a sensor that knows every site."""
    full = in_time_base(obs.measurements, units.parse_utc(READ_EPOCH), one.scenario.epoch)
    return full, build_site_network(one.scenario.components["sensor"], registry, full)


def arc_report(one, obs: ObjectObservations, arcs: Any, registry: Registry) -> ArcFit | None:
    """The latest arc's links and the residual ladder of the others for the converged fit ``one``
    (an :class:`~cistrack.fitting.from_observations.ObjectFit` of the latest arc); ``arcs`` are the
    arc settings (:class:`cistrack.fitting.arcs.ArcSettings`). None when there is no fit."""
    if not one.ok or one.run is None:
        return None
    full, sensor = _everything(one, obs, registry)
    r = one.result
    explained = r.n_rejected <= EXPLAINED_REJECTED * (r.n_used + r.n_rejected)
    link_gap = arcs.arc_gap_days if explained else arcs.link_gap_days
    dynamics = getattr(one, "dynamics", None) or one.run.context.dynamics  # with the burns the fit found
    return latest_arc_fit(dynamics, sensor, full, r, one.choices.options, arcs.arc_gap_days, link_gap)


def kept_observations(obs: ObjectObservations, report: ArcFit) -> ObjectObservations:
    """``obs`` reduced to the rows the arc report's fit kept (rows in time order)."""
    keep = np.zeros(len(obs.measurements), dtype=bool)
    keep[np.asarray(report.rows, dtype=int)] = True
    return dataclasses.replace(obs, measurements=obs.measurements.subset(keep))


def add_findings(one, registry: Registry, say: Callable[[str], None]) -> None:
    """``one.determination``, ``one.events`` and ``one.burn_sensitivity`` of a converged fit
    (nothing otherwise)."""
    if not one.ok or one.run is None:
        return
    ctx = one.run.context
    dynamics = getattr(one, "dynamics", None) or ctx.dynamics  # with the burns the fit found
    say(f"{one.designation}: how well the orbit is determined; impacts and closest approaches")
    one.determination = determination(one.result, dynamics, ctx.sensor, ctx.measurements)
    one.events = fit_events(dynamics, one.result, epoch=one.scenario.epoch)
    one.burn_sensitivity = burn_sensitivity(one.result, fitted_dynamics(dynamics, one.result), ctx.sensor,
                                            ctx.measurements)
