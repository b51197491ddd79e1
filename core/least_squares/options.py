"""Settings of the least-squares fit."""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from cistrack.errors import ParameterError

__all__ = ["FitOptions", "fit_option_problem", "AREA_TO_MASS", "AREA_TO_MASS_MODES"]

AREA_TO_MASS = "area_to_mass_m2_kg"
"""The dynamics parameter the ``area_to_mass`` option estimates: C_R A/m, m^2/kg."""
AREA_TO_MASS_MODES = ("off", "solve", "auto")


@dataclass(frozen=True)
class FitOptions:
    """Settings of :func:`cistrack.least_squares.fit_orbit`.

    Attributes
    ----------
    max_iterations : int
        Levenberg-Marquardt iterations per pass (a pass: fit with a fixed set of rejected
        observations).
    step_tolerance : float
        Converged when the Gauss-Newton step is smaller than this in units of the estimate's
        uncertainty: sqrt(dx^T N dx) < step_tolerance (N the normal matrix).
    rms_tolerance : float
        Converged when an accepted step changes the weighted RMS by less than this, relatively
        (with the damping back at or below its initial value).
    stall_step : float
        The cost's numerical floor, in sigmas: a pass whose damped step does not lower the cost
        while the Gauss-Newton step is below this has converged (more damping would only shorten
        the step); one whose damped steps stop lowering the cost (damping above ``max_damping``)
        with a larger Gauss-Newton step has not.
    damping, damping_factor, max_damping : float
        Initial Levenberg-Marquardt damping (relative to the normal matrix's diagonal), its
        factor after a rejected / accepted step, and the damping at which the iteration stops.
    reject_outliers : bool
        Chi-square outlier rejection with readmission (:mod:`cistrack.least_squares.outliers`).
    reject_sigma : float
        Rejection threshold as a Gaussian sigma level (3: chi-square 11.83 for two components).
    robust_threshold : bool
        Scale the threshold by the median chi-square while it exceeds the noise model's.
    max_reject_fraction : float
        At most this share of the observations is rejected.
    max_passes : int
        Fit-then-reject passes before giving up on a settled rejected set.
    use_range : bool
        Fit components named "range" too (default: angles only; range is an IOD aid).
    max_condition : float
        Condition number (unit-diagonal normal matrix) above which the arc is declared to leave a
        direction unobservable (an :class:`cistrack.least_squares.UnobservableWarning` and a message).
        Measured on the 9:2 NRHO seen from one site every 40 min: 1e7-2e8 for arcs of 2-5 hours,
        1e5 for 20 hours over two nights, 1e3-1e4 for three days.
    max_weak_sigma_km : float
        Also declared unobservable when the one-sigma position displacement along the weakest
        direction exceeds this, km (2,000-22,000 km for those 2-5 hour arcs, 5 km for three days).
    min_weak_sigma_km : float
        The condition number flags an arc only while that one-sigma displacement exceeds this, km
        (0: the condition number alone). The condition number does not change with the number of
        observations, only with their geometry: 4,200 observations in 7 dense tracklets over 14
        days from 3 sites (a simulated halo orbit) measured 8.85e7 with the weakest direction known
        to 80 m. Below 1 km (the default) a direction is determined by every standard this
        package uses (a range sigma of 1e-4 of the range is 3.6 km at GEO distance).
    max_rms : float
        A converged iteration whose weighted RMS exceeds this is reported as not converged: the
        orbit does not fit the observations (a wrong local minimum from a poor start, or a wrong
        model). Measured: the 9:2 NRHO in the ephemeris model, from a start 53,000 km and 50 m/s
        off, settles at weighted RMS 3,300, 96,000 km from the truth.
    sensor_steps : (6,) float or None
        Central-difference steps of the measurement Jacobian (LU, VU); None: the default.
    area_to_mass : str
        The radiation pressure's C_R A/m (m^2/kg) as a seventh unknown: "off" (default: not
        estimated; the fit is the 6-parameter one, bit for bit), "solve" (always estimated) or
        "auto" (estimated where the arc supports it: :mod:`cistrack.least_squares.area_to_mass`).
        Needs dynamics that offer the parameter (``ephemeris``).
    """

    max_iterations: int = 30
    step_tolerance: float = 1e-6
    rms_tolerance: float = 1e-10
    stall_step: float = 1e-2
    damping: float = 1e-3
    damping_factor: float = 10.0
    max_damping: float = 1e8
    reject_outliers: bool = True
    reject_sigma: float = 3.0
    robust_threshold: bool = True
    max_reject_fraction: float = 0.5
    max_passes: int = 10
    use_range: bool = False
    max_condition: float = 1e7
    max_weak_sigma_km: float = 1000.0
    max_rms: float = 100.0
    sensor_steps: Any = None
    area_to_mass: str = "off"
    min_weak_sigma_km: float = 1.0

    def __post_init__(self) -> None:
        for f in fields(self):
            why = fit_option_problem(f.name, getattr(self, f.name))
            if why:
                raise ParameterError(f"fit option {f.name} = {getattr(self, f.name)!r}: {why}")


def _is_number(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


def _finite(v: Any) -> bool:
    try:
        return math.isfinite(v)
    except OverflowError:  # an integer too large for a float
        return False


def _count(v: Any) -> str | None:
    ok = isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_)) and v >= 1
    return None if ok else "must be an integer >= 1"


def _positive(v: Any) -> str | None:
    return None if _is_number(v) and _finite(v) and v > 0 else "must be a finite number > 0"


def _non_negative(v: Any) -> str | None:
    return None if _is_number(v) and _finite(v) and v >= 0 else "must be a finite number >= 0"


def _growth(v: Any) -> str | None:
    return None if _is_number(v) and _finite(v) and v > 1 else "must be a finite number > 1"


def _fraction(v: Any) -> str | None:
    return None if _is_number(v) and 0 <= v < 1 else "must be a number in [0, 1)"


def _switch(v: Any) -> str | None:
    return None if isinstance(v, bool) else "must be true or false"


def _mode(v: Any) -> str | None:
    if isinstance(v, str) and v in AREA_TO_MASS_MODES:
        return None
    return ("must be one of " + ", ".join(AREA_TO_MASS_MODES)
            + " (estimate the radiation pressure's area-to-mass ratio: never, always, where the arc supports it)")


def _steps(v: Any) -> str | None:
    if v is None:
        return None
    seq = isinstance(v, (list, tuple)) or (isinstance(v, np.ndarray) and v.ndim == 1)
    ok = seq and len(v) == 6 and all(_is_number(x) and _finite(x) and x > 0 for x in v)
    return None if ok else "must be 6 positive numbers (LU, VU)"


_CHECKS = {
    "max_iterations": _count, "max_passes": _count, "step_tolerance": _positive, "rms_tolerance": _positive,
    "stall_step": _positive, "damping": _positive, "max_damping": _positive, "reject_sigma": _positive,
    "max_condition": _positive, "max_weak_sigma_km": _positive, "max_rms": _positive,
    "min_weak_sigma_km": _non_negative,
    "damping_factor": _growth, "max_reject_fraction": _fraction, "reject_outliers": _switch,
    "robust_threshold": _switch, "use_range": _switch, "area_to_mass": _mode, "sensor_steps": _steps,
}


def fit_option_problem(name: str, value: Any) -> str | None:
    """What is wrong with ``value`` for the :class:`FitOptions` field ``name`` ("must be ...", its
    type checked before its range), or None when it is admissible."""
    return _CHECKS[name](value)
