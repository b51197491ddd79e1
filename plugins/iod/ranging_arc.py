"""From the seed's fit to the whole arc: the least squares extended over more and more tracklets.

A fit over a few tracklets predicts the observations a little beyond them well, and far beyond
them poorly; started there, the least squares converges. :func:`extend_arc` therefore doubles the
fitted time span (about its middle) each time, takes every observation inside, and fits again from
the last solution (the state stays at the seed's epoch), until every observation is in. When a
doubled span fails, the next tracklet on each side is tried alone; when that fails too, the fit
stays over the span it has and the steps say so.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces import Dynamics, Sensor
from cistrack.least_squares import FitOptions, FitResult
from cistrack.model.measurement import MeasurementSet
from cistrack.units import tu_to_hours

from .ranging_search import _one_fit
from .tracklets import Attributable

__all__ = ["extend_arc", "tracklet_record"]

_OPTIONS = FitOptions(max_iterations=60, max_condition=1e30, max_weak_sigma_km=1e30)


def _next_span(times: np.ndarray, rows: np.ndarray, grow: float) -> np.ndarray:
    """Rows (sorted) of every observation within the span of ``rows`` widened ``grow`` times
    about its middle (at least to the next observation on each side)."""
    lo, hi = times[rows].min(), times[rows].max()
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * grow
    inside = (times >= mid - half) & (times <= mid + half)
    before, after = np.nonzero(times < lo)[0], np.nonzero(times > hi)[0]
    if before.size:
        inside[before[-1]] = True
    if after.size:
        inside[after[0]] = True
    return np.nonzero(inside | np.isin(np.arange(times.size), rows))[0]


def extend_arc(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, fit: FitResult, rows: np.ndarray,
               options: FitOptions = _OPTIONS) -> tuple[FitResult, np.ndarray, list[str]]:
    """(fit, rows it used (sorted), one line per step) of ``fit`` (over ``rows``) extended over
    every observation of ``ms`` (see the module docstring)."""
    rows = np.sort(np.asarray(rows, dtype=int))
    steps: list[str] = []
    while rows.size < len(ms):
        for grow in (2.0, 1.0):
            more = _next_span(ms.times, rows, grow)
            new = _one_fit(dynamics, sensor, ms.subset(more), fit.state, fit.epoch, options)
            if new is not None and new.converged:
                break
        else:
            steps.append(f"stopped at {rows.size} of {len(ms)} observations: the fit over {more.size} did not "
                         "converge")
            break
        span_h = tu_to_hours(float(ms.times[more].max() - ms.times[more].min()))
        steps.append(f"{more.size} observations over {span_h / 24.0:.2f} days: weighted RMS {new.rms:.3g}, "
                     f"{new.n_rejected} rejected")
        fit, rows = new, more
    return fit, rows, steps


def tracklet_record(atts: list[Attributable]) -> list[dict]:
    """One dict per tracklet: first time (TU), site, observations, misfit (sigma), consistent."""
    return [{"t_tu": float(a.t), "site": a.site, "n": int(a.indices.size), "first_row": int(a.indices[0]),
             "misfit_sigma": round(float(a.misfit), 2), "consistent": bool(a.consistent)} for a in atts]
