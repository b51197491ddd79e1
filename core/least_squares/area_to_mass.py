"""``area_to_mass="auto"``: estimate the radiation pressure's C_R A/m where the arc supports it.

The fit is made without the ratio (the 6-parameter fit) and, when the arc is long enough, again
with it (7 unknowns, started from the 6-parameter state and the dynamics' own ratio). The
7-parameter fit is kept when all of these hold:

- the arc spans at least :data:`MIN_ARC_DAYS` days (the radiation pressure of a rocket stage,
  ~0.008 m^2/kg, displaces a cislunar orbit by about 13 km in 10 days and 120 km in 30 days, most
  of which a 6-parameter orbit absorbs over a short arc);
- it converged;
- the estimate is significant: |A/m| / sigma >= :data:`MIN_SIGNIFICANCE`, sigma scaled by the
  noise scale when that exceeds 1 (so weights that are too optimistic do not make it significant);
- it is physical: 0 < A/m <= :data:`MAX_AREA_TO_MASS` m^2/kg (a negative or huge value means the
  data ask for some other missing force or a bad observation, not radiation pressure);
- the chi-square over the observations the 7-parameter fit used drops by at least
  :data:`MIN_CHI2_DROP` (measured on 2025-010D's 2026-04..05 arc: the 6-parameter fit rejects 12
  of 311 observations, the early ones that carry the pressure, and over the rows both fits used
  the drop is only 17, while with all 311 kept the chi-square rises by 7,760 = (A/m / sigma)^2
  from the estimate to A/m = 0 (a profile: the state refitted at A/m fixed)).

Otherwise the 6-parameter fit is returned, bit for bit the ``area_to_mass="off"`` fit, with the
reason in ``FitResult.area_to_mass_decision``.
"""
from __future__ import annotations

import dataclasses
import warnings
from typing import Any, Callable

import numpy as np

from cistrack.errors import MeasurementError, PropagationError
from cistrack.least_squares.errors import FitError
from cistrack.least_squares.options import AREA_TO_MASS, FitOptions
from cistrack.least_squares.result import FitResult
from cistrack.units import TU_S

__all__ = ["fit_area_to_mass_auto", "area_to_mass_verdict", "MIN_ARC_DAYS", "MIN_SIGNIFICANCE",
           "MIN_CHI2_DROP", "MAX_AREA_TO_MASS"]

MIN_ARC_DAYS = 10.0
"""Shortest arc, days, over which "auto" tries the ratio."""
MIN_SIGNIFICANCE = 3.0
"""|A/m| / sigma at or above which the estimate counts as significant."""
MIN_CHI2_DROP = 9.0
"""Chi-square drop (1 degree of freedom: 3 sigma) the ratio must bring over the common observations."""
MAX_AREA_TO_MASS = 1.0
"""Largest C_R A/m, m^2/kg, accepted as radiation pressure (solar sails reach ~0.1)."""


def _chi2_drop(six: FitResult, seven: FitResult) -> float:
    """chi-square of ``six`` minus that of ``seven`` over the rows ``seven`` used (``six``'s post-fit
    residuals of the rows it rejected count: a 6-parameter fit that rejects the observations
    which carry the radiation pressure must not look as good as one that explains them)."""
    used = ~np.asarray(seven.residuals.rejected, bool)
    return float(np.sum(np.asarray(six.residuals.chi2)[used]) - np.sum(np.asarray(seven.residuals.chi2)[used]))


def area_to_mass_verdict(six: FitResult, seven: FitResult) -> str | None:
    """Why ``seven`` (a fit with the ratio) should not replace ``six`` (without it), or None when
    it should (module docstring)."""
    if not seven.converged:
        return "the fit with it did not converge"
    value, sigma = seven.parameter(AREA_TO_MASS)
    scaled = sigma * max(1.0, float(seven.noise_scale) if np.isfinite(seven.noise_scale) else 1.0)
    what = f"estimate {value:.4g} +- {scaled:.2g} m^2/kg"
    if abs(value) < MIN_SIGNIFICANCE * scaled:
        return f"{what} is not significant (|A/m| / sigma {abs(value) / scaled:.2f} < {MIN_SIGNIFICANCE:g})"
    if not 0.0 < value <= MAX_AREA_TO_MASS:
        return f"{what} is not physical (outside (0, {MAX_AREA_TO_MASS:g}] m^2/kg)"
    drop = _chi2_drop(six, seven)
    if drop < MIN_CHI2_DROP:
        return f"{what} lowers the chi-square by only {drop:.3g} (< {MIN_CHI2_DROP:g})"
    return None


def _arc_days(measurements: Any) -> float:
    t = np.asarray(measurements.times, dtype=float)
    return float((t.max() - t.min()) * TU_S / 86400.0)


def _decided(result: FitResult, why: str) -> FitResult:
    return dataclasses.replace(result, area_to_mass_decision=why)


def fit_area_to_mass_auto(fit: Callable[[np.ndarray, FitOptions], FitResult], dynamics: Any, measurements: Any,
                          state: np.ndarray, *, options: FitOptions) -> FitResult:
    """:func:`cistrack.least_squares.fit_orbit` with ``area_to_mass="auto"`` (module docstring):
    the fit without the ratio, or with it where the arc supports it; ``state`` (6,) LU, VU at the
    fit epoch; ``fit(start, options)`` is fit_orbit of ``measurements`` with ``dynamics`` from
    ``start``. The returned result's ``area_to_mass_decision`` says which and why."""
    six = fit(state, dataclasses.replace(options, area_to_mass="off"))
    if AREA_TO_MASS not in tuple(getattr(dynamics, "solve_for_parameters", ())):
        return _decided(six, "not estimated: the dynamics has no radiation-pressure parameter (use 'ephemeris')")
    days = _arc_days(measurements)
    if days < MIN_ARC_DAYS:
        return _decided(six, f"not estimated: the arc spans {days:.3g} days (< {MIN_ARC_DAYS:g})")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seven = fit(six.state, dataclasses.replace(options, area_to_mass="solve"))
    except (FitError, PropagationError, MeasurementError) as exc:
        return _decided(six, f"not estimated: the fit with it failed ({exc})")
    why = area_to_mass_verdict(six, seven)
    if why is not None:
        return _decided(six, f"not estimated: {why}")
    value, sigma = seven.parameter(AREA_TO_MASS)
    return _decided(seven, f"estimated ({value:.4g} +- {sigma:.2g} m^2/kg over {days:.3g} days, "
                           f"chi-square lower by {_chi2_drop(six, seven):.3g})")
