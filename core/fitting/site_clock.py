"""The clock test of ``cistrack fit``: one site's times off by a constant, found in a fit of several
sites (:mod:`cistrack.least_squares.site_timing`) and confirmed by the fit with them corrected."""
from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

__all__ = ["ClockFinding", "clock_off", "consider_spread", "MOVED_BOUND"]

MOVED_BOUND = 22.5
"""Mahalanobis^2 (6 dof, about 1e-3) of the orbit with a site's times corrected, in the covariance
of the fit without the correction, beyond which that covariance misses the clock error: the fit
is not clean. Within it the clock is worth a word, not a refusal (the development set of 2025-010D:
P13's times about 11 s late, a chi-square of 17, the orbit moved well within its sigmas)."""


class ClockFinding(NamedTuple):
    """A site's clock offset that explains a fit: in words; how far correcting it moves the orbit
    (Mahalanobis^2 in the uncorrected fit's covariance, times the noise scale squared above 1);
    and ``spread`` (6, 6) LU, VU: what the uncorrected fit's state covariance lacks for it
    (:func:`consider_spread`)."""

    words: str
    moved_m2: float
    spread: np.ndarray


def consider_spread(timing, offset_s: float, sigma_s: float) -> np.ndarray:
    """(6, 6) LU, VU: ``S S^T (offset_s^2 + sigma_s^2)``, S the state's linearised sensitivity to the
    site's offset (``timing.absorbed_per_s``, per second: a
    :class:`~cistrack.least_squares.site_timing.SiteTiming`). A fit kept without the correction
    takes the offset as 0 while the data put it at ``offset_s`` +- ``sigma_s`` (a clock, or a site's
    position, which shifts its rows much as a clock does): its covariance holds the offset as a
    consider parameter of that spread about 0, so the corrected orbit lies within it. A site 6 km
    from where its code put it had been read as a clock 6.2 +- 1.1 s off, kept "well determined",
    and the truth lay at Mahalanobis^2 56."""
    s = np.asarray(timing.absorbed_per_s, dtype=float)[:6]
    return np.outer(s, s) * (offset_s ** 2 + sigma_s ** 2)


def clock_off(ctx, one, r) -> ClockFinding | None:
    """The clock offset of one site that explains what ``r`` (the ballistic fit of ``one``, an
    :class:`~cistrack.fitting.from_observations.ObjectFit`) leaves, or None: the site whose offset
    removes the most chi-square, beyond :func:`~cistrack.least_squares.site_timing.timing_limit`,
    and the fit with its times corrected clean (converged, nothing
    :func:`~cistrack.least_squares.burn_search.suspicion` or
    :func:`~cistrack.least_squares.burn_search.screen_suspicion` names)."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.result import sigma_factor
    from cistrack.least_squares.site_timing import site_timings, timing_limit

    try:
        timings = site_timings(ctx.dynamics, ctx.sensor, ctx.measurements, r)
    except (CistrackError, np.linalg.LinAlgError):
        return None
    if not timings or not timings[0].drop > timing_limit():
        return None
    best = timings[0]
    fixed = _corrected_fit(ctx, one, r, best)
    if fixed is None:
        return None
    f, offset, sigma = fixed
    d = np.asarray(f.state, dtype=float) - np.asarray(r.state, dtype=float)
    moved = float(d @ np.linalg.solve(np.asarray(r.covariance) * sigma_factor(r.noise_scale) ** 2, d))
    when = "late" if offset > 0 else "early"
    other = (f"site {timings[1].site}'s (with two sites only their difference is measured: or {timings[1].site}'s "
             f"{'early' if offset > 0 else 'late'} by as much)" if len(timings) == 2 else "the other sites'")
    words = (f"site {best.site}'s times look {abs(offset):.3g} +- {sigma:.2g} s {when} against {other} (the "
             f"offset removes a chi-square of {best.drop:.0f}; {timing_limit():.1f} is noise at 1e-4): a clock or position error "
             f"at {best.site}, or times of the exposure's start rather than its middle? With its times {abs(offset):.3g} s "
             f"{'earlier' if offset > 0 else 'later'} the fit is clean (weighted RMS {f.rms:.2f}) and its orbit moves "
             f"by Mahalanobis^2 {moved:.3g} in this fit's covariance")
    return ClockFinding(words, moved, consider_spread(best, offset, sigma))


def _corrected_fit(ctx, one, r, timing):
    """(fit, offset s, sigma s) of ``one``'s observations with ``timing.site``'s times corrected by
    the offset (refined once at the corrected fit), its epoch ``r``'s, when that fit is clean;
    else None."""
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
