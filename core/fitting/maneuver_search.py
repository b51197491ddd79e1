"""Maneuvers in ``cistrack fit``: a fit that an impulsive burn explains is never a clean "converged".

A ballistic fit that looks like an object that maneuvered (a contiguous block of rejections, a
large RMS, no convergence: :func:`cistrack.least_squares.burn_search.suspicion`) is searched for
burns (:func:`cistrack.least_squares.burn_search.search_maneuvers`); each burn kept becomes an entry
of ``fit.json``'s ``maneuvers`` (:func:`maneuver_record`) and the fit the one with the burns.
"""
from __future__ import annotations

import numpy as np

from cistrack import units
from cistrack.least_squares.impulse_fit import BurnEstimate

__all__ = ["maneuver_record"]


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
    """Search the converged or suspect fit of ``one`` (an
    :class:`~cistrack.fitting.from_observations.ObjectFit`) for burns when it looks like an object
    that maneuvered; with burns kept, ``one.result`` becomes the fit with them, ``one.dynamics`` the
    model that flies it and ``one.maneuvers`` their records; the fit's messages say what was found
    (or that nothing explains a suspect fit)."""
    from dataclasses import replace

    from cistrack.least_squares.burn_search import search_maneuvers, suspicion

    r = one.result
    if r is None or one.run is None:
        return
    why = suspicion(r)
    if not why:
        return
    ctx = one.run.context
    say(f"{one.designation}: the ballistic fit looks like a maneuver ({why}); searching for burns")
    found = search_maneuvers(ctx.dynamics, ctx.sensor, ctx.measurements, r, one.choices.options, say)
    if not found.burns:
        one.result = replace(r, messages=tuple(r.messages) + (
            f"the fit looks like an object that maneuvered ({why}), but no impulsive burn in the gaps "
            "between the observations explains it",))
        return
    times = np.asarray(ctx.measurements.times, dtype=float)
    one.maneuvers = [maneuver_record(b, w, float(times[times > b.t][0]), one.scenario.epoch)
                     for b, w in zip(found.burns, found.windows)]
    one.dynamics = found.dynamics
    text = "; ".join(f"a burn of {m['delta_v_ms']:.3f} +- {m['delta_v_sigma_ms']:.3f} m/s at {m['t_burn_utc'][:16]}"
                     for m in one.maneuvers)
    one.result = replace(found.result, messages=tuple(found.result.messages) + (
        f"the ballistic fit looked like a maneuver ({why}); fitted with {len(found.burns)} impulsive "
        f"burn(s): {text}",))
