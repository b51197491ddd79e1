"""Burn fits started where the orbits of the arc's two sides meet.

The burn search's fits start from the ballistic fit's orbit with the delta-v at zero
(:mod:`cistrack.least_squares.burn_search`). Where that orbit follows neither side of the burn, the
joint fit from there can run off (a halo orbit's 1 m/s burn 13.7 days into a 20-day arc: from the
ballistic start, weighted RMS 5,695 at the burn's true time), and the linearised screen that ranks
the gaps about it can miss the right one. Split at a gap instead:

1. the observations before the gap and those after it are each fitted alone as a ballistic arc
   (from the current orbit); both must converge with every direction observable, so each side
   needs observations on at least :data:`MIN_SIDE_NIGHTS` nights;
2. the two orbits are carried across the gap; where they pass closest (a local minimum of their
   distance, at most :data:`MEET_STARTS` of them, the nearest first) is a start for the burn's
   time, and the difference of their velocities there for its delta-v;
3. the arc is fitted in full with the burn there (state: the after side's orbit carried to the
   fit's epoch); when that fit rejects more observations than the two sides' fits together, again
   with those the sides rejected left out of its first pass, and the cheaper fit is kept (a gross
   outlier in the first pass had pulled a joint fit along the delta-v's weak direction until a
   whole night of the other side was rejected, from the truth itself; the other way, a first
   night left out of the first pass was not readmitted); a fit that stops unconverged is fitted
   once more from where it stopped (:func:`_continued`).

Each side fit costs about as much as one full fit, so the search makes these fits only when its
ordinary fits leave the arc unexplained (:func:`cistrack.least_squares.burn_search.search_maneuvers`
searching ``again``).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.errors import PropagationError
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.impulse_fit import (MS_PER_VU, BurnArc, BurnEstimate, ImpulseFit, capped_cost, fit_impulses,
                                                refit_moved)
from cistrack.least_squares.result import FitResult
from cistrack.least_squares.trajectory import arc_states
from cistrack.model.measurement import MeasurementSet

__all__ = ["Split", "split_candidates", "split_fit", "meet_starts", "side_nights", "MIN_SIDE_NIGHTS", "MEET_STARTS",
           "MEET_POINTS", "NIGHT_HOURS", "SPLIT_GAPS", "SPLIT_TRIED"]

MIN_SIDE_NIGHTS = 2
"""Nights of observations each side of a gap needs before the split is tried: one tracklet fits
a family of orbits, not one."""
NIGHT_HOURS = 3.0
"""Observations closer than this belong to one night (:func:`side_nights`)."""
MEET_STARTS = 3
"""Local minima of the two orbits' distance over the gap tried as burn starts, nearest first."""
MEET_POINTS = 200
"""Times across the gap at which the two orbits' distance is evaluated."""
SPLIT_GAPS = 2
"""Gaps fitted in full from their meeting points: those whose sides' orbits pass closest."""
SPLIT_TRIED = 16
"""Gaps whose sides are fitted, the longest first: every gap of a survey file (3-5 exposures a
tracklet, a few tracklets a night), the gaps between nights of a dense campaign (112 gaps in 8
days of three sites: 20 s of side fits for all of them)."""


def side_nights(times: np.ndarray) -> int:
    """Nights among observation ``times`` (TU): groups separated by more than :data:`NIGHT_HOURS`."""
    t = np.sort(np.asarray(times, dtype=float))
    if t.size == 0:
        return 0
    return 1 + int(np.sum(np.diff(t) > units.hours_to_tu(NIGHT_HOURS)))


def _gravity_only(arc: BurnArc) -> Any:
    """The arc's fit options without the area-to-mass ratio: a side's short arc cannot measure it
    (solved for on a few nights it left the model's range at -7,697 m^2/kg)."""
    return None if arc.options is None else replace(arc.options, area_to_mass="off")


def _side(arc: BurnArc, about: FitResult, flown: Any, rows: np.ndarray, edge: int,
          side_ok: Callable[[FitResult], bool]) -> FitResult | None:
    """The ballistic fit of the observations ``rows`` (K,) bool alone, its epoch at their ``edge``
    (0: first, -1: last), started from ``about``'s orbit flown by ``flown``; None unless it converges
    with every direction observable and ``side_ok`` accepts it."""
    sub: MeasurementSet = arc.measurements.subset(rows)
    t0 = float(sub.times[edge])
    try:
        x = arc_states(flown, about.state, about.epoch, np.array([t0]))[0]
        with warnings.catch_warnings():  # an unobservable side is this step's answer, not a warning
            warnings.simplefilter("ignore", UnobservableWarning)
            fit = fit_orbit(flown, arc.sensor, sub, x, t0, options=_gravity_only(arc))
    except (FitError, PropagationError, np.linalg.LinAlgError):
        return None
    return fit if fit.converged and not fit.unobservable and side_ok(fit) else None


@dataclass(frozen=True)
class Split:
    """The arc split at one gap.

    gap : (float, float)          TU, the gap
    before, after : (K,) bool     the observations on each side
    fits : (FitResult, FitResult) each side's ballistic fit alone
    starts : list of (float, (3,) float, float)   burn time TU, delta-v synodic m/s and the
                                  orbits' distance there (LU), nearest first (:func:`meet_starts`)
    """

    gap: tuple[float, float]
    before: np.ndarray
    after: np.ndarray
    fits: tuple[FitResult, FitResult]
    starts: list[tuple[float, np.ndarray, float]]


def meet_starts(flown: Any, before: FitResult, after: FitResult,
                gap: tuple[float, float]) -> list[tuple[float, np.ndarray, float]]:
    """(time TU, delta-v (3,) synodic m/s, distance LU) where the ``before`` and ``after`` orbits,
    both flown by ``flown`` across ``gap`` (TU), pass closest: at most :data:`MEET_STARTS` local
    minima of their distance, the nearest first."""
    grid = np.linspace(gap[0], gap[1], MEET_POINTS)
    xb = arc_states(flown, before.state, before.epoch, grid)
    xa = arc_states(flown, after.state, after.epoch, grid)
    d = np.linalg.norm(xa[:, :3] - xb[:, :3], axis=1)
    lower = np.r_[True, d[1:] <= d[:-1]] & np.r_[d[:-1] <= d[1:], True]
    order = [int(k) for k in np.flatnonzero(lower)[np.argsort(d[lower], kind="stable")]][:MEET_STARTS]
    return [(float(grid[k]), (xa[k, 3:] - xb[k, 3:]) * MS_PER_VU, float(d[k])) for k in order]


def split_candidates(arc: BurnArc, about: FitResult, flown: Any, gaps: list[tuple[float, float]],
                     side_ok: Callable[[FitResult], bool] = lambda fit: True) -> list[Split]:
    """The splits at ``gaps`` (TU; the :data:`SPLIT_TRIED` longest) whose sides each have
    :data:`MIN_SIDE_NIGHTS` nights and determine their orbits alone (started from ``about``'s orbit flown by ``flown``, the burns
    found so far), nearest meeting first."""
    t = np.asarray(arc.measurements.times, dtype=float)
    out = []
    for gap in sorted(gaps, key=lambda g: g[0] - g[1])[:SPLIT_TRIED]:
        before, after = t <= gap[0], t >= gap[1]
        if min(side_nights(t[before]), side_nights(t[after])) < MIN_SIDE_NIGHTS:
            continue
        fb = _side(arc, about, flown, before, -1, side_ok)
        fa = None if fb is None else _side(arc, about, flown, after, 0, side_ok)
        if fa is None:
            continue
        try:
            out.append(Split(gap, before, after, (fb, fa), meet_starts(flown, fb, fa, gap)))
        except PropagationError:
            continue
    return sorted(out, key=lambda s: s.starts[0][2])


def _rows_out(arc: BurnArc, split: Split) -> np.ndarray:
    """(K,) bool: the arc's observations that a side's fit rejected."""
    out = np.zeros(arc.measurements.times.size, dtype=bool)
    for fit, rows in zip(split.fits, (split.before, split.after)):
        out[np.flatnonzero(rows)] = np.asarray(fit.residuals.rejected, dtype=bool)
    return out


def _continued(arc: BurnArc, one: ImpulseFit) -> ImpulseFit:
    """``one``, fitted once more from where it stopped when it did not converge (its burns' delta-v
    and rejected observations carried): from a meeting point a halo orbit's fit crawled down a
    curved valley for its 300 iterations to weighted RMS 1.04 and stopped unconverged."""
    if one.fit.converged:
        return one
    again = refit_moved(arc, one.fit, one.burns, 0, one.burns[0].t)
    return again if capped_cost(again.fit, arc.prior) <= capped_cost(one.fit, arc.prior) else one


def split_fit(arc: BurnArc, about: FitResult, flown: Any, split: Split,
              known: list[BurnEstimate]) -> ImpulseFit | None:
    """The best full fit (smallest capped cost) of the arc with the ``known`` burns and one more in
    ``split``'s gap, started at each of its meeting points (module docstring), its state at
    ``about``'s epoch; None when no start gives a fit. ``flown`` flies the ``known`` burns."""
    try:
        x = arc_states(flown, split.fits[1].state, split.fits[1].epoch, np.array([about.epoch]))[0]
    except PropagationError:
        return None
    out = _rows_out(arc, split)
    best = None
    for tb, dv, _ in split.starts:
        for first_out in (None, out):
            try:
                one = _continued(arc, fit_impulses(arc, x, about.epoch, [*(b.t for b in known), tb],
                                                   [*(b.delta_v_ms for b in known), dv], rejected=first_out))
            except (FitError, PropagationError):
                continue
            cost = capped_cost(one.fit, arc.prior)
            if best is None or cost < best[0]:
                best = (cost, tb, one)
            if one.fit.n_rejected <= int(out.sum()):  # no more rejected than the sides': no outlier pulled it
                break
    if best is None:
        return None
    cost, tb, one = best
    new = next(k for k, b in enumerate(one.burns) if b.t == tb)
    return ImpulseFit(one.burns, one.fit, new, np.array([cost]), np.array([tb]))
