"""The line of variations (LOV): least-squares solutions along the weakest direction of a fit.

When an arc determines one direction of the state much less well than the others (a short arc's
range, or a short arc after a months-long gap), the set of orbits that fit the data is a long,
thin and *bent* valley of the chi-square, and the linearised covariance of the fit describes only
its bottom: on Example 3 (3:1 NRHO, 150-day gap, seed 3007) the least-squares solution lay 20 km
from the truth with a chi-square only 11.8 below the truth's, yet the truth was 80 sigmas off along
the sharpest direction of the fit's covariance; the valley had curved away from the straight line.

The LOV follows the valley (Milani et al. 2005, "Multiple solutions for asteroid orbits", the
method behind OrbFit's and Find_Orb's handling of weakly determined orbits). With P the fit's
covariance and N = P^-1, v is the weakest direction (the eigenvector of P with the largest
eigenvalue in unit-diagonal scaling, which makes it independent of the units of each coordinate),
normalised so that v^T N v = 1. For sigma = +-step, +-2 step, ... the point of the LOV is the
least-squares solution on the hyperplane

    v^T N (x - x*) = sigma,

found by the fit's own Levenberg-Marquardt with the constraint as a stiff quadratic penalty, each
point started from its neighbour. A side stops when its chi-square exceeds the nominal one by
``max_delta_chi2`` or a point does not converge. To first order the points are x* + sigma v with
chi-square chi2* + sigma^2, and the covariance of each point on its hyperplane is the fit's
covariance conditioned on sigma; far from x* they follow the curve.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from cistrack.errors import MeasurementError, PropagationError
from cistrack.least_squares.solve_for_parameters import fitted_dynamics
from cistrack.least_squares.differential_correction import _one_pass, _Problem
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.observability import km_apart
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.progress import reported_to, tell
from cistrack.least_squares.result import FitResult
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet

__all__ = ["LovPoint", "weakest_direction", "line_of_variations", "line_weights", "sample_line", "line_summary",
           "line_minima", "line_reach", "REACH_DELTA_CHI2", "widened_to_hold"]

REACH_DELTA_CHI2 = 9.0
"""The line's points within this chi-square of its lowest are the orbits the data allow at 3 sigma
(one dimension): :func:`line_reach`."""
_STIFFNESS = 1e8  # penalty per squared sigma off the hyperplane: the point stays within 1e-4 sigma


@dataclass(frozen=True)
class LovPoint:
    """One point of the line of variations.

    sigma : float            position along the line, in sigmas of the weakest direction at x*
    state : (6,) float       least-squares solution on the hyperplane, LU, VU, at the fit's epoch
    chi2 : float             its chi-square over the arc
    covariance : (6, 6)      its covariance on the hyperplane (conditioned on sigma), LU, VU
    """

    sigma: float
    state: np.ndarray
    chi2: float
    covariance: np.ndarray


def weakest_direction(covariance: np.ndarray) -> np.ndarray:
    """The fit's weakest direction (6,), LU, VU, scaled to one sigma: v^T P^-1 v = 1.

    The eigenvector of the covariance (6, 6) with the largest eigenvalue after scaling to unit
    diagonal, signed so that its largest position component is positive."""
    p = 0.5 * (covariance + covariance.T)
    d = np.sqrt(np.diag(p))
    _, vec = np.linalg.eigh(p / np.outer(d, d))
    v = vec[:, -1] * d
    v = v / np.sqrt(v @ np.linalg.solve(p, v))
    return -v if v[int(np.argmax(np.abs(v[:3])))] < 0 else v


def _conditional_covariance(prob: _Problem, x: np.ndarray, w: np.ndarray) -> np.ndarray | None:
    """(N + penalty)^-1 at x (weighted residuals w there): the covariance on the hyperplane; None
    when not positive definite."""
    n, _ = prob.normal(prob.jacobian(x), w, x, np.ones(w.shape[0], dtype=bool))
    d = np.sqrt(np.abs(np.diag(n)))
    try:
        c = np.linalg.inv(np.linalg.cholesky(n / np.outer(d, d)))
    except np.linalg.LinAlgError:
        return None
    cov = (c.T @ c) / np.outer(d, d)
    return 0.5 * (cov + cov.T) if np.all(np.isfinite(cov)) else None


def line_of_variations(dynamics: Dynamics, sensor: Sensor, measurements: MeasurementSet, fit: FitResult, *,
                       step: float = 0.5, max_sigma: float = 4.0, max_delta_chi2: float = 16.0,
                       options: FitOptions | None = None) -> list[LovPoint]:
    """Points of the line of variations of ``fit`` (a converged :func:`cistrack.least_squares.fit_orbit` result
    over ``measurements``, all of them used), ordered by sigma, the nominal solution included.

    Parameters
    ----------
    dynamics, sensor, measurements
        As given to the fit (parameters the fit estimated, e.g. the area-to-mass ratio, are held at
        their estimates: :func:`cistrack.least_squares.solve_for_parameters.fitted_dynamics`).
    fit : FitResult
        The nominal solution x* and its covariance P at ``fit.epoch``.
    step : float
        Spacing of the points, sigmas of the weakest direction.
    max_sigma : float
        Farthest point on each side, sigmas.
    max_delta_chi2 : float
        A side ends at the first point whose chi-square exceeds the nominal one by more.
    options : FitOptions, optional
        Iteration settings of each point's fit (outlier rejection is not applied).

    Returns
    -------
    list of :class:`LovPoint` (the nominal point's covariance is P - v v^T: P conditioned on
    sigma = 0); just the nominal one when ``step`` or ``max_sigma`` leave no other point.
    """
    opts = FitOptions(reject_outliers=False) if options is None else options
    dynamics = fitted_dynamics(dynamics, fit)  # solve-for parameters held at the fit's estimates
    model = MeasurementModel(sensor, measurements, use_range=opts.use_range, steps=opts.sensor_steps)
    x0 = np.asarray(fit.state, dtype=float)
    v = weakest_direction(fit.covariance)
    nominal = LovPoint(0.0, x0, float(fit.chi2), fit.covariance - np.outer(v, v))  # P given sigma = 0
    if not (step > 0 and max_sigma >= step):
        return [nominal]
    normal = np.linalg.inv(fit.covariance) @ v  # v^T N (x - x*) = sigma defines the hyperplanes
    points = [nominal]
    for sign in (1.0, -1.0):
        x = x0.copy()
        for k in range(1, int(np.floor(max_sigma / step + 1e-9)) + 1):
            sigma = sign * k * step
            centre = x0 + sigma * v
            prob = _Problem(dynamics, model, fit.epoch, (centre, _STIFFNESS * np.outer(normal, normal)))
            try:
                with warnings.catch_warnings(), reported_to(None):   # one line per point, below
                    warnings.simplefilter("ignore")
                    x, _, ok = _one_pass(prob, x + sign * step * v, np.ones(len(measurements), dtype=bool),
                                         opts, [])
                    w, _ = prob.evaluate(x)
                    cov = _conditional_covariance(prob, x, w) if ok else None
            except (PropagationError, MeasurementError, np.linalg.LinAlgError, FloatingPointError):
                break
            chi2 = float(np.sum(w ** 2))
            if cov is None or not np.isfinite(chi2) or chi2 - fit.chi2 > max_delta_chi2:
                break
            points.append(LovPoint(sigma, x.copy(), chi2, cov))
            tell(len(measurements), f"    line of variations at {sigma:+g} sigma: chi-square {chi2 - fit.chi2:+.4g} "
                                    "from the fit's")
    return sorted(points, key=lambda p: p.sigma)


def _square_root(cov: np.ndarray) -> np.ndarray:
    """A factor L (6, 6) with L L^T = cov for a positive semi-definite cov (eigen-decomposition:
    the nominal point's covariance is singular along the line)."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    return v * np.sqrt(np.clip(w, 0.0, None))


def line_weights(points: list[LovPoint], step: float, direction: np.ndarray) -> np.ndarray:
    """Probability (K,) of each point's stretch of the line: its Laplace evidence on the hyperplane,
    exp(-chi2 / 2) |C + step^2 v v^T|^(1/2) (v the weakest direction, which makes every point's
    covariance regular), normalised."""
    along = step ** 2 * np.outer(direction, direction)
    logw = np.array([-0.5 * p.chi2 + 0.5 * np.linalg.slogdet(p.covariance + along)[1] for p in points])
    w = np.exp(logw - logw.max())
    return w / w.sum()


def sample_line(points: list[LovPoint], n: int, rng: np.random.Generator, step: float,
                direction: np.ndarray) -> np.ndarray:
    """States (n, 6) drawn along the line of variations: a point k chosen by :func:`line_weights`,
    an offset u uniform within half a step of it, the state on the line at sigma_k + u (quadratic
    through the point and its neighbours, so the draws follow the bend; linear at an end; along
    ``direction`` when the line has one point), plus the point's covariance on its hyperplane.

    ``points`` are those of :func:`line_of_variations` (spaced ``step`` apart), ``direction`` the
    weakest direction (6,) it followed (:func:`weakest_direction`)."""
    k_of = rng.choice(len(points), size=n, p=line_weights(points, step, direction))
    u = rng.uniform(-0.5, 0.5, size=n) * step
    z = rng.standard_normal((n, 6))
    x = np.empty((n, 6))
    states = np.array([p.state for p in points])
    for k in np.unique(k_of):
        idx = np.flatnonzero(k_of == k)
        uk = u[idx, None]
        xk = states[k]
        lo, hi = k > 0, k < len(points) - 1
        if lo and hi:
            d1 = (states[k + 1] - states[k - 1]) / (2 * step)
            d2 = (states[k + 1] - 2 * xk + states[k - 1]) / step ** 2
            on_line = xk + uk * d1 + 0.5 * uk ** 2 * d2
        elif hi:
            on_line = xk + uk * (states[k + 1] - xk) / step
        elif lo:
            on_line = xk + uk * (xk - states[k - 1]) / step
        else:
            on_line = xk + uk * direction
        x[idx] = on_line + z[idx] @ _square_root(points[k].covariance).T
    return x


def line_summary(points: list[LovPoint], fit: FitResult) -> dict:
    """How far the line of variations departs from the linearised fit, for a report.

    With v the weakest direction and N the fit's normal matrix, each point's departure from the
    straight line is d = x_k - (x* + sigma_k v), measured as sqrt(d^T N d) (sigmas of the fit)
    and in position km; its chi-square rise is compared with the linear sigma^2. Returns a dict:
    ``sigma_range`` [lowest, highest], ``max_departure_sigma``, ``max_departure_km``,
    ``max_chi2_excess`` (largest |delta chi2 - sigma^2|), ``followed`` (the line has points on
    both sides of the nominal one: its fits converged there) and ``linear`` (followed, with the
    departure below 1 sigma and the chi-square within 1 of sigma^2 everywhere: the covariance
    describes the solutions; a line whose first fits failed checks nothing)."""
    v = weakest_direction(fit.covariance)
    n = np.linalg.inv(fit.covariance)
    dep_sigma, dep_km, excess = [], [], []
    for p in points:
        d = p.state - (fit.state + p.sigma * v)
        dep_sigma.append(float(np.sqrt(max(d @ n @ d, 0.0))))
        dep_km.append(km_apart(p.state, fit.state + p.sigma * v))
        excess.append(abs(p.chi2 - fit.chi2 - p.sigma ** 2))
    out = {"sigma_range": [float(min(p.sigma for p in points)), float(max(p.sigma for p in points))],
           "max_departure_sigma": max(dep_sigma), "max_departure_km": max(dep_km),
           "max_chi2_excess": float(max(excess))}
    lo, hi = out["sigma_range"]
    out["followed"] = bool(lo < 0.0 < hi)
    out["linear"] = bool(out["followed"] and out["max_departure_sigma"] < 1.0 and out["max_chi2_excess"] < 1.0)
    out["minima"] = line_minima(points)
    out["reach"] = line_reach(points)
    return out


def line_minima(points: list[LovPoint]) -> list[dict]:
    """The minima of the chi-square along the line ``points`` (ordered by sigma): points lower than
    both neighbours, and an end point lower than its one neighbour (the line was cut there, so the
    minimum may lie beyond), lowest first, as dicts: ``sigma``, ``delta_chi2`` (above the lowest),
    ``offset_km`` (position from the lowest at the epoch) and ``at_end``."""
    if not points:
        return []
    chi2 = np.array([p.chi2 for p in points])
    last = len(points) - 1
    idx = [k for k in range(len(points))
           if (k == 0 or chi2[k] < chi2[k - 1]) and (k == last or chi2[k] < chi2[k + 1])]
    idx.sort(key=lambda k: chi2[k])
    best = points[idx[0]].state
    return [{"sigma": float(points[k].sigma), "delta_chi2": float(chi2[k] - chi2[idx[0]]),
             "offset_km": km_apart(points[k].state, best), "at_end": bool(len(points) > 1 and k in (0, last))}
            for k in idx]


def line_reach(points: list[LovPoint], delta_chi2: float = REACH_DELTA_CHI2) -> dict:
    """How far the orbits the data allow reach along the line ``points`` (ordered by sigma): those
    within ``delta_chi2`` of the lowest chi-square. A dict: ``sigma_range`` [lowest, highest sigma
    of such points], ``max_offset_km`` (their farthest position from the lowest point at the
    epoch) and ``open`` (an end point of the line is among them: the allowed orbits go on beyond it)."""
    chi2 = np.array([p.chi2 for p in points])
    inside = np.flatnonzero(chi2 <= chi2.min() + delta_chi2)
    best = points[int(np.argmin(chi2))].state
    return {"sigma_range": [float(points[inside[0]].sigma), float(points[inside[-1]].sigma)],
            "max_offset_km": max(km_apart(points[k].state, best) for k in inside),
            "open": bool(inside[0] == 0 or inside[-1] == len(points) - 1)}


def widened_to_hold(cov: np.ndarray, offsets: np.ndarray, bound: float = 9.0) -> np.ndarray:
    """C + s M (n, n): ``cov`` C widened along the ``offsets`` d (M, n) from its mean (the orbits of
    a line of variations that bends away from C), M the mean of d d^T and s >= 0 the least (to 1 %)
    that puts every d within the ellipsoid d^T (C + s M)^-1 d <= ``bound`` (9: 3 sigma along d);
    C itself when it already holds them all."""
    d = np.asarray(offsets, dtype=float)
    m = np.einsum("mi,mj->ij", d, d) / len(d)

    def inside(s: float) -> bool:
        return bool(np.max(np.einsum("mi,ij,mj->m", d, np.linalg.inv(cov + s * m), d)) <= bound)

    if inside(0.0):
        return cov
    hi = 1.0
    while not inside(hi) and hi < 1e12:
        hi *= 4.0
    lo = hi / 4.0 if hi > 1.0 else 0.0
    while hi - lo > 0.01 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if inside(mid) else (mid, hi)
    return cov + hi * m
