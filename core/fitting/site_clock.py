"""The clock test of ``cistrack fit``: one site's times off by a constant, found in a fit of several
sites (:mod:`cistrack.least_squares.site_timing`) and confirmed by the fit with them corrected."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["clock_off"]


def clock_off(ctx, one, r) -> str:
    """Words saying that one site's clock explains what ``r`` (the ballistic fit of ``one``, an
    :class:`~cistrack.fitting.from_observations.ObjectFit`) leaves, "" when none does: the site whose
    offset removes the most chi-square, beyond :func:`~cistrack.least_squares.site_timing.timing_limit`,
    and the fit with its times corrected clean (converged, nothing
    :func:`~cistrack.least_squares.burn_search.suspicion` or
    :func:`~cistrack.least_squares.burn_search.screen_suspicion` names)."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.site_timing import site_timings, timing_limit

    try:
        timings = site_timings(ctx.dynamics, ctx.sensor, ctx.measurements, r)
    except (CistrackError, np.linalg.LinAlgError):
        return ""
    if not timings or not timings[0].drop > timing_limit():
        return ""
    best = timings[0]
    fixed = _corrected_fit(ctx, one, r, best)
    if fixed is None:
        return ""
    f, offset, sigma = fixed
    when = "late" if offset > 0 else "early"
    return (f"site {best.site}'s times look {abs(offset):.3g} +- {sigma:.2g} s {when} against the other sites' "
            f"(the offset removes a chi-square of {best.drop:.0f}; {timing_limit():.1f} is noise at 1e-4): a clock "
            f"error at {best.site}? With its times {abs(offset):.3g} s {'earlier' if offset > 0 else 'later'} the fit "
            f"is clean (weighted RMS {f.rms:.2f}); correct them in the file, or leave {best.site}'s observations out")


def _corrected_fit(ctx, one, r, timing):
    """(fit, offset s, sigma s) of ``one``'s observations with ``timing.site``'s times corrected by
    the offset (refined once at the corrected fit), when that fit is clean; else None."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.burn_search import screen_suspicion, suspicion
    from cistrack.least_squares.differential_correction import fit_orbit
    from cistrack.least_squares.site_timing import site_timings, with_site_times_shifted

    opts = one.choices.options
    if one.reject_fraction is not None:
        opts = replace(opts, max_reject_fraction=one.reject_fraction)
    offset, sigma, start = timing.offset_s, timing.sigma_s, r.state
    try:
        for _ in range(2):
            ms = with_site_times_shifted(ctx.measurements, timing.site, -offset)
            f = fit_orbit(ctx.dynamics, ctx.sensor, ms, start, r.epoch, options=opts)
            again = {t.site: t for t in site_timings(ctx.dynamics, ctx.sensor, ms, f)}.get(timing.site)
            if again is None:
                return None
            offset, sigma, start = offset + again.offset_s, again.sigma_s, f.state
        clean = f.converged and not suspicion(f) and not screen_suspicion(ctx.dynamics, ctx.sensor, ms, f, opts)
    except (CistrackError, np.linalg.LinAlgError):
        return None
    return (f, offset, sigma) if clean else None
