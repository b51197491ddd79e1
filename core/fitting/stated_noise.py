"""Whether a fit's residuals say that the observations' stated uncertainties are too small.

A file whose rmsRA/rmsDec are some N times too small gives residuals some N times the stated
noise on every night, at every site and in both angles; the fit then fails, and the maneuver
search blames the misfit on burns (probe N1: rmsRA = rmsDec = 0.04" on 0.85" data: "a 981 m/s
burn"). A maneuver leaves some nights on the orbit and others off it; a fit caught in a wrong
minimum leaves residuals of tens of arcseconds. :func:`stated_too_small` tells the first case,
and the fit says it before any maneuver words, with a setting that replaces the file's own
uncertainties (the ADES readers' ``sigma_from_file = false``).
"""
from __future__ import annotations

import numpy as np

from cistrack import units

__all__ = ["stated_too_small", "too_small_words", "MIN_SCALE", "BAND", "ASTROMETRIC_NOISE_ARCSEC", "NIGHT_GAP_DAYS"]

MIN_SCALE = 3.0
"""The residuals' RMS over the stated noise (used rows, both angles) from which the stated noise
is judged at all."""
BAND = (0.4, 2.5)
"""Each night's and each site-and-angle's RMS of normalised residuals lies within this factor of
the whole fit's for the scale to be one uniform multiple (a night of 2-6 observations scatters by
about a third; a maneuver leaves the nights before it far below)."""
ASTROMETRIC_NOISE_ARCSEC = 3.0
"""The largest noise (arcsec on the sky) read as ordinary astrometry: residuals uniformly larger
are a wrong orbit, not stated uncertainties too small."""
NIGHT_GAP_DAYS = 0.5
"""Observations more than this apart fall on different nights."""


def _groups(table, used: np.ndarray, angles: list[int]) -> list[np.ndarray]:
    """The normalised residuals of the used rows by night (gaps over :data:`NIGHT_GAP_DAYS`; 2 or
    more rows) and by site and angle (3 or more rows)."""
    z = np.asarray(table.normalised, dtype=float)[used][:, angles]
    t = np.asarray(table.times, dtype=float)[used]
    order = np.argsort(t)
    night = np.empty(t.size, dtype=int)
    night[order] = np.concatenate([[0], np.cumsum(np.diff(t[order]) > units.days_to_tu(NIGHT_GAP_DAYS))])
    out = [z[night == n] for n in np.unique(night) if np.sum(night == n) >= 2]
    sites = np.asarray(table.sites).astype(str)[used]
    out += [z[sites == s, j] for s in np.unique(sites) if np.sum(sites == s) >= 3 for j in range(len(angles))]
    return out


def stated_too_small(table) -> tuple[float, float] | None:
    """(the factor, the noise the residuals show in arcsec on the sky) when the residuals of the
    :class:`~cistrack.least_squares.residual_table.ResidualTable` ``table`` are one uniform multiple
    of at least :data:`MIN_SCALE` of the stated noise (every group of :func:`_groups` within
    :data:`BAND`) and that noise is ordinary astrometry (at most :data:`ASTROMETRIC_NOISE_ARCSEC`);
    None otherwise."""
    if table is None or len(table) == 0:
        return None
    angles = [j for j, unit in enumerate(table.units) if unit == "arcsec"]
    used = ~np.asarray(table.rejected, dtype=bool)
    if not angles or used.sum() < 8:
        return None
    z = np.asarray(table.normalised, dtype=float)[used][:, angles]
    scale = float(np.sqrt(np.mean(z ** 2)))
    if not scale >= MIN_SCALE:
        return None
    lo, hi = BAND
    if any(not lo * scale <= float(np.sqrt(np.mean(g ** 2))) <= hi * scale for g in _groups(table, used, angles)):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        stated = np.abs(np.asarray(table.o_c, dtype=float)[used][:, angles] / z)
    noise = scale * float(np.nanmedian(stated))
    return (scale, noise) if noise <= ASTROMETRIC_NOISE_ARCSEC else None


def too_small_words(table) -> str:
    """The sentence that the stated uncertainties look N times too small, with the settings that
    weight the observations by the noise they show; "" when :func:`stated_too_small` finds not."""
    found = stated_too_small(table)
    if found is None:
        return ""
    scale, noise = found
    return (f"the stated uncertainties look {scale:.2g} times too small: the residuals are about {scale:.2g} times "
            f"them on every night, at every site and in both angles (a scatter of {noise:.2g} arcsec, ordinary "
            "astrometry), where a maneuver would leave some nights on the orbit; what follows is judged with "
            f"weights that tight. Refit with --set measurements.reader.sigma_arcsec={noise:.2g} (and, for files that "
            "state their own rmsRA/rmsDec, --set measurements.reader.sigma_from_file=false)")
