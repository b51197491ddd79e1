"""The clock test of ``cistrack fit``: one site's times off by a constant, found in a fit of several
sites (:mod:`cistrack.least_squares.site_timing`) and confirmed by the fit with them corrected."""
from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

__all__ = ["ClockFinding", "clock_off", "consider_spread", "MOVED_BOUND", "CLEAN_FALSE_ALARM"]

MOVED_BOUND = 22.5
"""Mahalanobis^2 (6 dof, about 1e-3) of the orbit with a site's times corrected, in the covariance
of the fit without the correction, beyond which that covariance misses the clock error: the fit
is not clean. Within it the clock is worth a word, not a refusal (the development set of 2025-010D:
P13's times about 11 s late, a chi-square of 17, the orbit moved well within its sigmas)."""


class ClockFinding(NamedTuple):
    """Site clock offsets that explain a fit: in words; how far correcting them moves the orbit
    (Mahalanobis^2 in the uncorrected fit's covariance, times the noise scale squared above 1);
    and ``spread`` (6, 6) LU, VU: what the uncorrected fit's state covariance lacks for them (each
    site's :func:`consider_spread`, its sensitivity taken at the uncorrected fit)."""

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
    """The clock offsets of one site, or two, that explain what ``r`` (the ballistic fit of
    ``one``, an :class:`~cistrack.fitting.from_observations.ObjectFit`) leaves, or None: the site
    whose offset removes the most chi-square, beyond
    :func:`~cistrack.least_squares.site_timing.timing_limit`, and, when the fit with its times
    corrected is not clean, the site whose offset is then largest beyond it too (one more); the fit
    with them corrected clean (:func:`_clean`)."""
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
    fixed = _corrected_fit(ctx, one, r, [best.site])
    if fixed is not None and not fixed[2]:
        second = _next_site(ctx, fixed[0], fixed[1], best.site)
        fixed = None if second is None else _corrected_fit(ctx, one, r, [best.site, second])
    if fixed is None or not fixed[2]:
        return None
    f, offsets = fixed[0], fixed[3]
    d = np.asarray(f.state, dtype=float) - np.asarray(r.state, dtype=float)
    moved = float(d @ np.linalg.solve(np.asarray(r.covariance) * sigma_factor(r.noise_scale) ** 2, d))
    words = (f"{_offset_words(offsets, timings)} ({best.site}'s offset removes a chi-square of {best.drop:.0f}; "
             f"{timing_limit():.1f} is noise at 1e-4): a clock or position error at {' and '.join(offsets)}, or times "
             f"of the exposure's start rather than its middle? With {_corrections(offsets)} the fit is clean (weighted "
             f"RMS {f.rms:.2f}) and its orbit moves by Mahalanobis^2 {moved:.3g} in this fit's covariance")
    at = {t.site: t for t in timings}
    return ClockFinding(words, moved, sum(consider_spread(at[x], *offsets[x]) for x in offsets if x in at))


def _offset_words(offsets: dict, timings: list) -> str:
    """"site X's times look ... against ..." for the corrected ``offsets`` {site: (offset s, sigma s)}."""
    def one(site: str) -> str:
        offset, sigma = offsets[site]
        return f"{abs(offset):.3g} +- {sigma:.2g} s {'late' if offset > 0 else 'early'}"

    first, *more = list(offsets)
    if more:
        return f"site {first}'s times look {one(first)} and site {more[0]}'s {one(more[0])} against the other sites'"
    if len(timings) == 2:
        other = timings[1].site
        return (f"site {first}'s times look {one(first)} against site {other}'s (with two sites only their difference "
                f"is measured: or {other}'s {'early' if offsets[first][0] > 0 else 'late'} by as much)")
    return f"site {first}'s times look {one(first)} against the other sites'"


def _corrections(offsets: dict) -> str:
    return " and ".join(f"{site}'s times {abs(o):.3g} s {'earlier' if o > 0 else 'later'}" for site, (o, _) in offsets.items())


def _next_site(ctx, f, ms, done: str) -> str | None:
    """The site other than ``done`` whose offset in ``f`` (the fit of ``ms``, ``done``'s times
    corrected) removes the most chi-square beyond the limit, or None."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.site_timing import site_timings, timing_limit

    try:
        rest = [t for t in site_timings(ctx.dynamics, ctx.sensor, ms, f) if t.site != done]
    except (CistrackError, np.linalg.LinAlgError):
        return None
    return rest[0].site if rest and rest[0].drop > timing_limit() else None


def _corrected_fit(ctx, one, r, sites: list[str]):
    """(fit, measurements, clean, {site: (offset s, sigma s)}) of ``one``'s observations with the
    ``sites``' times corrected by their offsets (measured at ``r``, refined twice at the corrected
    fit), its epoch ``r``'s (clean: :func:`_clean`); None when that fit cannot be made."""
    from cistrack.errors import CistrackError
    from cistrack.least_squares.differential_correction import fit_orbit
    from cistrack.least_squares.site_timing import site_timings, with_site_times_shifted

    opts = one.choices.options
    if one.reject_fraction is not None:
        opts = replace(opts, max_reject_fraction=one.reject_fraction)
    offsets, f, ms = {site: (0.0, 0.0) for site in sites}, r, ctx.measurements
    try:
        for _ in range(3):
            found = {t.site: t for t in site_timings(ctx.dynamics, ctx.sensor, ms, f)}
            if any(site not in found for site in sites):
                return None
            offsets = {site: (offsets[site][0] + found[site].offset_s, found[site].sigma_s) for site in sites}
            ms = ctx.measurements
            for site, (offset, _) in offsets.items():
                ms = with_site_times_shifted(ms, site, -offset)
            f = fit_orbit(ctx.dynamics, ctx.sensor, ms, f.state, r.epoch, options=opts)
        return f, ms, _clean(ctx, ms, f, opts), offsets
    except (CistrackError, np.linalg.LinAlgError):
        return None


CLEAN_FALSE_ALARM = 1e-4
"""A fit whose chi-square exceeds its quantile at 1 - this (its degrees of freedom) is not clean
(:func:`_clean`)."""


def _clean(ctx, ms, f, opts) -> bool:
    """Whether ``f``, the fit of ``ms``, is clean: converged, nothing
    :func:`~cistrack.least_squares.burn_search.suspicion` or
    :func:`~cistrack.least_squares.burn_search.screen_suspicion` names, and its chi-square within
    its quantile at :data:`CLEAN_FALSE_ALARM`. With two sites' clocks off and one corrected, a fit
    of weighted RMS 1.45 over 49 observations (chi-square about 190 for 92 degrees of freedom)
    had been called clean."""
    from cistrack.least_squares.burn_search import screen_suspicion, suspicion
    from cistrack.least_squares.chi_square import chi2_ppf

    dof = int(f.n_used) * len(f.residuals.names) - 6 - len(f.parameter_names)
    if not (f.converged and dof > 0 and f.chi2 <= chi2_ppf(1.0 - CLEAN_FALSE_ALARM, dof)):
        return False
    return not suspicion(f) and not screen_suspicion(ctx.dynamics, ctx.sensor, ms, f, opts)
