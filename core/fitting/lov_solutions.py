"""A poorly determined fit's line of variations followed until the data rule it out, and the
better solutions found along it.

A short arc (one night from one site) leaves a long, bent valley of the chi-square along its
weakest direction, and the valley may hold more than one minimum: one site's 4-hour night of an
NRHO object (11 observations) converged to a minimum 28,917 km from the truth, while the line of
variations, followed past its linear 3 sigma, fell to a second minimum 19 sigma along it with a
chi-square 3.3 lower, where the truth was (Milani et al. 2005, "Multiple solutions for asteroid
orbits", found such pairs of solutions in short asteroid arcs).

So by default (``fit.lov = "auto"``) the line of a poorly determined fit goes on, half a sigma
at a time, until the chi-square exceeds the nominal one by :data:`AUTO_DELTA_CHI2` (or
:data:`AUTO_MAX_SIGMAS` sigmas of the linear covariance). When a point of it fits better than the
nominal solution by more than :data:`BETTER_BY`, the least squares is started again from there;
a converged fit that uses at least as many observations and has the lower chi-square replaces the
first, and the line is followed again from it
(:func:`cistrack.least_squares.line_of_variations.line_minima` then names the other minima along it).
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from cistrack.errors import MeasurementError, PropagationError
from cistrack.fitting.fit_record_check import within_reach
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.line_of_variations import LovPoint, line_of_variations
from cistrack.least_squares.observability import km_apart, to_km
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.result import FitResult

__all__ = ["AUTO_DELTA_CHI2", "AUTO_MAX_SIGMAS", "BETTER_BY", "LOV_STEP", "follow_line", "better_solution",
           "within_cislunar_reach"]

AUTO_DELTA_CHI2 = 16.0
"""A side of the default line ends at its first point whose chi-square exceeds the nominal one by
more (4 sigma in one dimension: the 3-sigma extent, delta chi-square 9, lies inside)."""
AUTO_MAX_SIGMAS = 40.0
"""The default line's farthest point each side, sigmas of the fit's linear covariance."""
BETTER_BY = 1.0
"""A point of the line whose chi-square is lower than the nominal one by more than this starts the
least squares again."""
LOV_STEP = 0.5
"""Spacing of the line's points, sigmas of the weakest direction."""
MIN_ITERATIONS = 300
"""Each point's Levenberg-Marquardt gets at least this many iterations (the constraint's stiff
penalty slows it)."""


def follow_line(dynamics, sensor, measurements, result: FitResult, options: FitOptions, sigmas: float | None
                ) -> list[LovPoint]:
    """The line of variations of ``result`` over the observations it used: to +-``sigmas`` each
    side, or with None to the chi-square rise :data:`AUTO_DELTA_CHI2` (at most
    :data:`AUTO_MAX_SIGMAS`), every :data:`LOV_STEP` sigma."""
    used = measurements.subset(~np.asarray(result.residuals.rejected, dtype=bool))
    opts = replace(options, reject_outliers=False, max_iterations=max(options.max_iterations, MIN_ITERATIONS))
    far, rise = (AUTO_MAX_SIGMAS, AUTO_DELTA_CHI2) if sigmas is None else (sigmas, float("inf"))
    return within_cislunar_reach(line_of_variations(dynamics, sensor, used, result, step=LOV_STEP, max_sigma=far,
                                                    max_delta_chi2=rise, options=opts))


def within_cislunar_reach(points: list[LovPoint]) -> list[LovPoint]:
    """``points`` cut, each side of the nominal solution, before the first state beyond 3e6 km or
    100 km/s (:func:`cistrack.fitting.fit_record_check.within_reach`): export and predict read no
    lov.csv with such a state, and a line through one is no cislunar orbit's."""
    if not points:
        return points
    ok = within_reach(to_km(np.array([p.state for p in points])))
    sig = np.array([p.sigma for p in points], dtype=float)
    hi = min((s for s, good in zip(sig, ok) if s > 0 and not good), default=np.inf)
    lo = max((s for s, good in zip(sig, ok) if s < 0 and not good), default=-np.inf)
    return [p for p, s in zip(points, sig) if lo < s < hi]


def better_solution(dynamics, sensor, measurements, result: FitResult, points: list[LovPoint],
                    options: FitOptions) -> FitResult | None:
    """The least squares over ``measurements`` started from the lowest point of the line when it
    fits better than ``result`` by more than :data:`BETTER_BY`; that fit when it converges, uses at
    least as many observations and has a chi-square lower by more than :data:`BETTER_BY`, else None.
    Its messages say where it was found."""
    low = min(points, key=lambda p: p.chi2, default=None)
    if low is None or not low.chi2 < result.chi2 - BETTER_BY:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UnobservableWarning)  # also in the result's messages
            again = fit_orbit(dynamics, sensor, measurements, low.state, result.epoch, options=options)
    except (FitError, PropagationError, MeasurementError, np.linalg.LinAlgError, FloatingPointError):
        return None
    if not (again.converged and again.n_used >= result.n_used and again.chi2 < result.chi2 - BETTER_BY):
        return None
    km = km_apart(again.state, result.state)
    found = (f"a better solution along the line of variations: started again from {low.sigma:+g} sigma of the first "
             f"solution, the fit's chi-square is {result.chi2 - again.chi2:.3g} lower (the first solution lies {km:,.0f} km "
             "from it at the epoch and fits worse)")
    return replace(again, messages=tuple(again.messages) + (found,))
