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

from cistrack.errors import MeasurementError, ParameterError, PropagationError
from cistrack.least_squares.errors import FitError
from cistrack.least_squares.options import AREA_TO_MASS, FitOptions
from cistrack.least_squares.result import FitResult, sigma_factor
from cistrack.units import TU_S

__all__ = ["fit_area_to_mass_auto", "area_to_mass_verdict", "estimate_doubt", "forced_decision", "joint_covariances", "MIN_ARC_DAYS", "MIN_SIGNIFICANCE",
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


def estimate_doubt(seven: FitResult) -> str | None:
    """Why the ratio ``seven`` estimated says nothing about the object (not significant, or not
    physical), or None."""
    value, sigma = seven.parameter(AREA_TO_MASS)
    scaled = sigma * sigma_factor(seven.noise_scale)
    what = f"estimate {value:.4g} +- {scaled:.2g} m^2/kg"
    if abs(value) < MIN_SIGNIFICANCE * scaled:
        return f"{what} is not significant (|A/m| / sigma {abs(value) / scaled:.2f} < {MIN_SIGNIFICANCE:g})"
    if not 0.0 < value <= MAX_AREA_TO_MASS:
        return f"{what} is not physical (outside (0, {MAX_AREA_TO_MASS:g}] m^2/kg)"
    return None


def forced_decision(result: FitResult) -> FitResult:
    """A fit made with ``area_to_mass="solve"``, its decision saying when the estimate is not
    significant or not physical (the arc does not determine the ratio: refit with "auto" or "off")."""
    if result.parameter(AREA_TO_MASS) is None or not result.converged:
        return result
    why = estimate_doubt(result)
    return result if why is None else _decided(result, f"estimated as asked (area_to_mass = 'solve'), but the {why}: "
                                                       "this arc does not determine it; fit again with 'auto' or 'off'")


def area_to_mass_verdict(six: FitResult, seven: FitResult) -> str | None:
    """Why ``seven`` (a fit with the ratio) should not replace ``six`` (without it), or None when
    it should (module docstring)."""
    if not seven.converged:
        return "the fit with it did not converge"
    doubt = estimate_doubt(seven)
    if doubt is not None:
        return doubt
    value, sigma = seven.parameter(AREA_TO_MASS)
    scaled = sigma * sigma_factor(seven.noise_scale)
    what = f"estimate {value:.4g} +- {scaled:.2g} m^2/kg"
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


def _one_orbit(dynamics: Any, state: np.ndarray, t0: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(states (K, 6), alive (K,) bool) of one orbit: :func:`_batch` of one state."""
    states, ok = _batch(dynamics, np.asarray(state, dtype=float)[None], t0, times)
    return states[:, 0], ok


def _with_values(dynamics: Any, names: tuple, values: np.ndarray) -> Any:
    return dynamics.with_parameters(**{n: float(v) for n, v in zip(names, values)})


def _parameter_partials(dynamics: Any, result: FitResult, times: np.ndarray) -> np.ndarray:
    """d x(t) / d p (K, 6, P) at ``times`` with the epoch state held: central differences with the
    steps of :mod:`.solve_for_parameters` (the trajectory is nearly linear in the area-to-mass
    ratio: its acceleration is exactly linear in it)."""
    from cistrack.least_squares.solve_for_parameters import STEPS, DEFAULT_STEP

    names, p = tuple(result.parameter_names), np.asarray(result.parameters, dtype=float)
    cols = []
    for j, name in enumerate(names):
        step = np.zeros(p.size)
        step[j] = STEPS.get(name, DEFAULT_STEP)
        up, _ = _one_orbit(_with_values(dynamics, names, p + step), result.state, result.epoch, times)
        down, _ = _one_orbit(_with_values(dynamics, names, p - step), result.state, result.epoch, times)
        cols.append((up - down) / (2.0 * step[j]))
    return np.stack(cols, axis=-1)


def _joint_linear(dynamics: Any, result: FitResult, times: np.ndarray) -> np.ndarray:
    """[Phi(t), dx(t)/dp] P_joint [Phi(t), dx(t)/dp]^T (K, 6, 6) at ``times``."""
    from cistrack.least_squares.trajectory import arc_states_and_stms

    names, p = tuple(result.parameter_names), np.asarray(result.parameters, dtype=float)
    _, stms = arc_states_and_stms(_with_values(dynamics, names, p), result.state, result.epoch, times)
    jac = np.concatenate([stms, _parameter_partials(dynamics, result, times)], axis=2)   # (K, 6, 6 + P)
    cov = np.einsum("kij,jl,kml->kim", jac, np.asarray(result.full_covariance, dtype=float), jac)
    return 0.5 * (cov + np.transpose(cov, (0, 2, 1)))


def _joint_points(x: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """The 2n sigma points (2n, n) of ``x`` (n,) and its joint ``cov`` (n, n), ``x +- sqrt(n) s_j``
    with ``s_j`` the columns of a Cholesky factor taken with the parameters first: all but 2P of the
    points then hold the parameters at their estimates (one model integrates them together).
    Any square root gives a valid unscented transform; the symmetric one
    (:func:`.unscented_prediction.sigma_points`) when the factor does not exist."""
    from cistrack.least_squares.unscented_prediction import sigma_points

    n = x.size
    order = np.r_[np.arange(6, n), np.arange(6)]
    c = 0.5 * (cov + cov.T)[np.ix_(order, order)]
    d = np.sqrt(np.clip(np.diag(c), 1e-300, None))
    try:
        low = np.linalg.cholesky(c / np.outer(d, d)) * d[:, None]
    except np.linalg.LinAlgError:
        return sigma_points(x, cov)
    root = np.empty_like(low)
    root[order] = low
    return np.vstack([x + np.sqrt(n) * root.T, x - np.sqrt(n) * root.T])


def _batch(dynamics: Any, states: np.ndarray, t0: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(states (K, N, 6), all alive (K,) bool) of ``states`` (N, 6) from ``t0`` at ``times`` (K,) TU
    in any order, forward and backward separately; not alive on and after a hit or a failure."""
    out, ok = np.full((times.size, states.shape[0], 6), np.nan), np.zeros(times.size, dtype=bool)
    for forward in (True, False):
        rows = np.flatnonzero(times >= t0 if forward else times < t0)
        if rows.size == 0:
            continue
        rows = rows[np.argsort(times[rows] if forward else -times[rows], kind="stable")]
        try:
            prop = dynamics.propagate(states, t0, times[rows])
        except PropagationError:
            continue
        out[rows] = np.asarray(prop.states, dtype=float)
        hit = np.asarray(prop.impact_time, dtype=float)[~np.asarray(prop.alive, dtype=bool)]
        ok[rows] = True if hit.size == 0 else ((times[rows] < hit.min()) if forward else (times[rows] > hit.max()))
    return out, ok


def _joint_unscented(dynamics: Any, result: FitResult, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(covariances (K, 6, 6), valid (K,)) by the unscented transform of the joint covariance of
    state and parameters (:func:`_joint_points`), each point's orbit integrated with its own
    parameter values, the points that share them in one call; not valid where an orbit hit a body
    or failed."""
    names, p = tuple(result.parameter_names), np.asarray(result.parameters, dtype=float)
    x = np.concatenate([np.asarray(result.state, dtype=float), p])
    points = _joint_points(x, np.asarray(result.full_covariance, dtype=float))
    everything = np.vstack([x[None], points])
    states = np.empty((times.size, everything.shape[0], 6))
    ok = np.ones(times.size, dtype=bool)
    values, group = np.unique(everything[:, 6:], axis=0, return_inverse=True)
    for g, v in enumerate(values):
        members = np.flatnonzero(group.reshape(-1) == g)
        try:
            model = _with_values(dynamics, names, v)
        except ParameterError:  # a sigma point beyond the values the dynamics allow: the linear map stands in
            return np.zeros((times.size, 6, 6)), np.zeros(times.size, dtype=bool)
        states[:, members], alive = _batch(model, everything[members, :6], result.epoch, times)
        ok &= alive
    d = states[:, 1:] - states[:, :1]
    spread = np.einsum("kni,knj->kij", d, d) / len(points)
    return 0.5 * (spread + np.transpose(spread, (0, 2, 1))), ok


def joint_covariances(dynamics: Any, result: FitResult, times: Any, covariance: str = "unscented"
                      ) -> tuple[np.ndarray, np.ndarray] | None:
    """The state covariance (K, 6, 6) [LU, VU] of a fit with solve-for parameters (the area-to-mass
    ratio) at ``times`` (K,) TU, carried from the **joint** covariance of state and parameters
    (``result.full_covariance``), so that the parameters' uncertainty widens it away from the fit
    epoch (there it is the state block). ``covariance`` "unscented": the sigma points of the joint
    covariance, each orbit with its own parameter values (as the events' mapping,
    :mod:`.events`, moves the model with each point); "linear": the transition matrices with the
    parameters' partials. Returns (covariances, linear (K,) bool: where a sigma-point orbit hit a
    body or failed, so the linear map stands in), or None when the fit estimated no parameter.
    ``dynamics`` is the model without or with the estimated values (they are set here)."""
    names = tuple(getattr(result, "parameter_names", ()))
    if not names or getattr(result, "full_covariance", None) is None:
        return None
    tt = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
    if covariance == "linear":
        return _joint_linear(dynamics, result, tt), np.ones(tt.size, dtype=bool)
    cov, ok = _joint_unscented(dynamics, result, tt)
    if not np.all(ok):
        cov[~ok] = _joint_linear(dynamics, result, tt[~ok])
    return cov, ~ok
