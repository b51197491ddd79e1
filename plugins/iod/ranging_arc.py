"""From the seed's fit to the whole arc: the least squares extended over more and more tracklets.

A fit over a few tracklets predicts the observations a little beyond them well, and far beyond
them poorly; started there, the least squares converges. :func:`extend_arc` therefore doubles the
fitted time span (about its middle) each time, takes every observation inside, and fits again from
the last solution (the state stays at the seed's epoch), until every observation is in. When a
doubled span fails, the next observation on each side is tried alone; when that fails too (a
tracklet days away, where the last fit's weak directions have grown), the fit is **bridged**: a
grid over the fit's two least determined directions (out to :data:`BRIDGE_SIGMAS` sigma) is
propagated at once, scored on the observations to be added (:func:`.ranging_search.score_states`)
and the least squares started from the best few. When that fails too, the fit stays over the span
it has and the steps say so. A step fits only when it converges with residuals below
:data:`.ranging_search.CLEAN_NOISE_SCALE` times the noise: a converged fit far above it sits in a
false minimum (an L2 Lyapunov orbit's last step, to a tracklet 11 days on, converged with
residuals 91 times the noise, 74,000 km off), and the steps after it would start from there.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces import Dynamics, Sensor
from cistrack.least_squares import FitOptions, FitResult
from cistrack.model.measurement import MeasurementSet
from cistrack.units import tu_to_hours

from .ranging_search import CLEAN_NOISE_SCALE, _one_fit, score_states
from .tracklets import Attributable

__all__ = ["extend_arc", "tracklet_record", "BRIDGE_SIGMAS"]

BRIDGE_SIGMAS = 30.0
"""Half-width of the bridging grid along each of the two weakest directions, in their sigmas."""
_BRIDGE_STEPS = (61, 31)   # grid points along the weakest and the second weakest direction

_OPTIONS = FitOptions(max_iterations=60, max_condition=1e30, max_weak_sigma_km=1e30, max_reject_fraction=0.1)
"""As the seed's fit (:mod:`.tracklet_ranging`): at most 10 % rejected."""


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


def _bridge(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, fit: FitResult, rows: np.ndarray,
            added: np.ndarray, options: FitOptions) -> FitResult | None:
    """The least squares over ``rows`` started from the best-scored states of a grid over the two
    least determined directions of ``fit``, scored on the rows ``added`` (see the module
    docstring); None when none of the best four converges."""
    w, v = np.linalg.eigh(0.5 * (fit.covariance + fit.covariance.T))
    axes = [v[:, -1] * np.sqrt(max(w[-1], 0.0)), v[:, -2] * np.sqrt(max(w[-2], 0.0))]
    a = np.linspace(-BRIDGE_SIGMAS, BRIDGE_SIGMAS, _BRIDGE_STEPS[0])
    b = np.linspace(-BRIDGE_SIGMAS, BRIDGE_SIGMAS, _BRIDGE_STEPS[1])
    grid = fit.state[None] + np.add.outer(a, np.zeros_like(b)).reshape(-1, 1) * axes[0] \
        + np.add.outer(np.zeros_like(a), b).reshape(-1, 1) * axes[1]
    score = score_states(dynamics, sensor, ms, added, grid, fit.epoch)
    sub = ms.subset(rows)
    for i in np.argsort(score, kind="stable")[:4]:
        if not np.isfinite(score[i]):
            break
        out = _one_fit(dynamics, sensor, sub, grid[i], fit.epoch, options)
        if _fits(out):
            return out
    return None


def _fits(fit: FitResult | None) -> bool:
    """The step's fit converged with residuals near the noise (below :data:`CLEAN_NOISE_SCALE`)."""
    return fit is not None and fit.converged and fit.noise_scale < CLEAN_NOISE_SCALE


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
            if _fits(new):
                break
        else:
            new = _bridge(dynamics, sensor, ms, fit, more, np.setdiff1d(more, rows), options)
            if new is None:
                steps.append(f"stopped at {rows.size} of {len(ms)} observations: the fit over {more.size} did not "
                             f"converge with residuals below {CLEAN_NOISE_SCALE:g} times the noise, bridged or not")
                break
            steps.append(f"bridged over the gap to {more.size} observations (a grid over the fit's two weakest "
                         "directions)")
        span_h = tu_to_hours(float(ms.times[more].max() - ms.times[more].min()))
        steps.append(f"{more.size} observations over {span_h / 24.0:.2f} days: weighted RMS {new.rms:.3g}, "
                     f"{new.n_rejected} rejected")
        fit, rows = new, more
    return fit, rows, steps


def tracklet_record(atts: list[Attributable]) -> list[dict]:
    """One dict per tracklet: first time (TU), site, observations, misfit (sigma), consistent."""
    return [{"t_tu": float(a.t), "site": a.site, "n": int(a.indices.size), "first_row": int(a.indices[0]),
             "misfit_sigma": round(float(a.misfit), 2), "consistent": bool(a.consistent)} for a in atts]
