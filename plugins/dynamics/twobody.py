"""Keplerian two-body motion, registered as dynamics "twobody", plus a closed-form propagator.

Inertial frame centred on the attracting body; states nondimensional (LU, VU, TU from
:mod:`cistrack.units`) so that the same filters and sensors work on it. The attracting body's
GM is given in km^3/s^2 and converted: gm = GM * TU_S^2 / LU_KM^3.

:func:`kepler_propagate` is the universal-variable solution (Stumpff functions, Newton's method on
the universal anomaly), vectorised over states; it serves tests and the Gauss IOD baseline.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack import units
from cistrack.interfaces.component import check_int, check_positive, check_range
from cistrack.errors import CistrackError
from cistrack.api import hookimpl
from cistrack.lazy import lazy_njit
from cistrack.interfaces.dynamics import Body
from cistrack.astro.primaries import EARTH_RADIUS_KM

from cistrack.propagation import CompiledDynamics

__all__ = ["TwoBody", "twobody_rhs", "kepler_propagate", "gm_nondimensional", "GM_EARTH_KM3S2"]

GM_EARTH_KM3S2: float = 398600.4418
"""Earth's gravitational parameter, km^3/s^2."""


def gm_nondimensional(gm_km3s2: float) -> float:
    """GM in km^3/s^2 -> LU^3/TU^2."""
    return float(gm_km3s2) * units.TU_S ** 2 / units.LU_KM ** 3


# compiled on first use (or inlined into the propagation kernels): listing plugins needs no numba
# no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
@lazy_njit(cache=True)
def twobody_rhs(t, y, p, out):
    """Kepler equations of motion: y (6,) [LU, VU] -> out (6,); p = [gm (LU^3/TU^2)]."""
    r2 = y[0] * y[0] + y[1] * y[1] + y[2] * y[2]
    c = -p[0] / (r2 * np.sqrt(r2))
    out[0] = y[3]
    out[1] = y[4]
    out[2] = y[5]
    out[3] = c * y[0]
    out[4] = c * y[1]
    out[5] = c * y[2]


def _stumpff(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stumpff functions C(z), S(z), accurate for all real z (series near 0)."""
    c = np.empty_like(z)
    s = np.empty_like(z)
    small = np.abs(z) < 0.1
    zs = z[small]
    # C = sum (-z)^k / (2k+2)!, S = sum (-z)^k / (2k+3)!
    cs = np.zeros_like(zs)
    ss = np.zeros_like(zs)
    term_c = np.full_like(zs, 0.5)
    term_s = np.full_like(zs, 1.0 / 6.0)
    for k in range(9):
        cs += term_c
        ss += term_s
        term_c = term_c * (-zs) / ((2 * k + 3) * (2 * k + 4))
        term_s = term_s * (-zs) / ((2 * k + 4) * (2 * k + 5))
    c[small], s[small] = cs, ss
    pos = (~small) & (z > 0)
    sq = np.sqrt(z[pos])
    c[pos] = (1.0 - np.cos(sq)) / z[pos]
    s[pos] = (sq - np.sin(sq)) / sq ** 3
    neg = (~small) & (z < 0)
    sq = np.sqrt(-z[neg])
    c[neg] = (np.cosh(sq) - 1.0) / (-z[neg])
    s[neg] = (np.sinh(sq) - sq) / sq ** 3
    return c, s


@dataclass(frozen=True)
class _UniversalProblem:
    """Per-state data of the universal-variable Kepler problem: r0v, v0v (N, 3) position and
    velocity; r0, rdotv, alpha (1/a) and dt (N,) (elliptic dt reduced below half a period);
    sqmu = sqrt(gm), gm in the states' units."""

    r0v: np.ndarray
    v0v: np.ndarray
    r0: np.ndarray
    rdotv: np.ndarray
    alpha: np.ndarray
    dt: np.ndarray
    gm: float
    sqmu: float


def _within_half_period(dt: np.ndarray, alpha: np.ndarray, gm: float) -> np.ndarray:
    """``dt`` (N,) less the whole periods of the elliptic states: whole revolutions change nothing."""
    ell = alpha > 1e-12
    period = np.full(dt.shape[0], np.inf)
    period[ell] = 2.0 * np.pi / np.sqrt(gm * alpha[ell] ** 3)
    dt = dt.copy()
    dt[ell] = dt[ell] - np.round(dt[ell] / period[ell]) * period[ell]
    return dt


def _universal_problem(s: np.ndarray, dt, gm: float) -> _UniversalProblem:
    """The problem for states ``s`` (N, 6) and times of flight ``dt`` (scalar or (N,))."""
    dt = np.broadcast_to(np.asarray(dt, dtype=float), (s.shape[0],)).astype(float)
    r0v, v0v = s[:, :3], s[:, 3:]
    r0 = np.linalg.norm(r0v, axis=1)
    if np.any(r0 <= 0) or not np.all(np.isfinite(s)):
        raise CistrackError("kepler_propagate: states must be finite with nonzero position")
    rdotv = np.sum(r0v * v0v, axis=1)
    alpha = 2.0 / r0 - np.sum(v0v * v0v, axis=1) / gm  # 1/a
    return _UniversalProblem(r0v, v0v, r0, rdotv, alpha, _within_half_period(dt, alpha, gm), gm, np.sqrt(gm))


def _anomaly_guess(p: _UniversalProblem) -> np.ndarray:
    """Initial universal anomaly (N,): elliptic from the mean motion, hyperbolic Vallado's log
    form, parabolic sqrt(gm) dt / r0."""
    sqmu, alpha, dt, r0 = p.sqmu, p.alpha, p.dt, p.r0
    chi = sqmu * alpha * dt
    hyp = alpha < -1e-12
    if np.any(hyp):
        a = 1.0 / alpha[hyp]
        sg = np.sign(dt[hyp])
        num = -2.0 * p.gm * alpha[hyp] * dt[hyp]
        den = p.rdotv[hyp] + sg * np.sqrt(-p.gm * a) * (1.0 - r0[hyp] * alpha[hyp])
        with np.errstate(divide="ignore", invalid="ignore"):
            guess = sg * np.sqrt(-a) * np.log(np.abs(num / den))
        chi[hyp] = np.where(np.isfinite(guess), guess, sqmu * dt[hyp] / r0[hyp])
    par = np.abs(alpha) <= 1e-12
    chi[par] = sqmu * dt[par] / r0[par]
    return chi


def _time_residual(p: _UniversalProblem, chi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time-of-flight residual F(chi) (times sqrt(gm)) and its derivative F' = r, both (N,)."""
    z = p.alpha * chi * chi
    c, sz = _stumpff(z)
    chi2 = chi * chi
    f = (p.rdotv / p.sqmu) * chi2 * c + (1.0 - p.alpha * p.r0) * chi2 * chi * sz + p.r0 * chi - p.sqmu * p.dt
    fp = (p.rdotv / p.sqmu) * chi * (1.0 - z * sz) + (1.0 - p.alpha * p.r0) * chi2 * c + p.r0
    return f, fp


def _bracket_fallback(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Where Newton leaves the bracket: its midpoint, or a step beyond its one finite end."""
    both = np.isfinite(lo) & np.isfinite(hi)
    return np.where(both, 0.5 * (lo + hi),
                    np.where(np.isfinite(lo), lo + 2.0 * np.maximum(np.abs(lo), 1.0),
                             hi - 2.0 * np.maximum(np.abs(hi), 1.0)))


def _solve_anomaly(p: _UniversalProblem, tol: float, max_iter: int) -> np.ndarray:
    """Universal anomaly (N,) solving F(chi) = 0. F increases monotonically (F' = r > 0): Newton's
    method, safeguarded by the bracket of signs seen so far."""
    chi = _anomaly_guess(p)
    n = chi.shape[0]
    lo = np.full(n, -np.inf)
    hi = np.full(n, np.inf)
    converged = np.zeros(n, dtype=bool)
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(max_iter):
            f, fp = _time_residual(p, chi)
            bad = ~np.isfinite(f)
            hi = np.where((f > 0) | (bad & (chi > 0)), np.minimum(hi, chi), hi)
            lo = np.where((f < 0) | (bad & (chi < 0)), np.maximum(lo, chi), lo)
            new = chi - f / fp
            outside = ~np.isfinite(new) | (new <= lo) | (new >= hi)
            new = np.where(outside, _bracket_fallback(lo, hi), new)
            step = new - chi
            chi = new
            converged = (np.abs(step) <= tol * np.maximum(1.0, np.abs(chi))) | (f == 0)
            if np.all(converged):
                break
    if not np.all(converged):
        raise CistrackError(f"kepler_propagate: universal-anomaly iteration did not converge for "
                            f"{int(np.sum(~converged))} state(s)")
    return chi


def _lagrange_states(p: _UniversalProblem, chi: np.ndarray) -> np.ndarray:
    """States (N, 6) after dt from the Lagrange coefficients f, g, fdot, gdot at anomaly ``chi``."""
    z = p.alpha * chi * chi
    c, sz = _stumpff(z)
    chi2 = chi * chi
    f = 1.0 - chi2 / p.r0 * c
    g = p.dt - chi2 * chi / p.sqmu * sz
    r = f[:, None] * p.r0v + g[:, None] * p.v0v
    rn = np.linalg.norm(r, axis=1)
    fdot = p.sqmu / (rn * p.r0) * (p.alpha * chi2 * chi * sz - chi)
    gdot = 1.0 - chi2 / rn * c
    v = fdot[:, None] * p.r0v + gdot[:, None] * p.v0v
    return np.concatenate([r, v], axis=1)


def kepler_propagate(states: np.ndarray, dt, gm: float, *, tol: float = 1e-14,
                     max_iter: int = 100) -> np.ndarray:
    """Closed-form Kepler propagation by universal variables.

    Parameters
    ----------
    states : (N, 6) or (6,) float
        Position and velocity relative to the attracting body (any consistent units).
    dt : float or (N,) float
        Time of flight, same time unit as gm's (may be negative).
    gm : float
        Gravitational parameter in the states' units (LU^3/TU^2 for nondimensional states).
    tol : float
        Newton stops when the anomaly's step is below tol x max(1, |chi|).
    max_iter : int
        Newton iterations at most.

    Returns
    -------
    (N, 6) or (6,) float: the states after ``dt``. Raises :class:`CistrackError` if Newton's
    iteration on the universal anomaly does not converge (it does for every non-degenerate orbit).
    """
    s = np.asarray(states, dtype=float)
    one = s.ndim == 1
    p = _universal_problem(s.reshape(-1, 6), dt, gm)
    out = _lagrange_states(p, _solve_anomaly(p, tol, max_iter))
    return out[0] if one else out


class TwoBody(CompiledDynamics):
    """Keplerian motion about a body at the origin of an inertial frame (LU, VU, TU).

    Parameters
    ----------
    gm_km3s2 : float
        Gravitational parameter of the central body, km^3/s^2 (Earth by default).
    body_radius_km : float
        Impact radius of the central body, km (0 disables impacts).
    rtol, atol : float
        Per-particle relative / absolute integration tolerances.
    max_steps : int
        Step limit per particle and call.
    """

    rhs = twobody_rhs

    def __init__(self, gm_km3s2: float = GM_EARTH_KM3S2, body_radius_km: float = EARTH_RADIUS_KM,
                 rtol: float = 1e-12, atol: float = 1e-13, max_steps: int = 5_000_000):
        self.gm_km3s2 = check_positive(self, "gm_km3s2", gm_km3s2)
        self.body_radius_km = check_range(self, "body_radius_km", body_radius_km, 0.0, 1e7)
        self.rtol = check_range(self, "rtol", rtol, 1e-15, 1e-2)
        self.atol = check_range(self, "atol", atol, 1e-18, 1e-2)
        self.max_steps = check_int(self, "max_steps", max_steps, minimum=1)

    @property
    def gm(self) -> float:
        """Gravitational parameter, LU^3/TU^2."""
        return gm_nondimensional(self.gm_km3s2)

    def params_vector(self) -> np.ndarray:
        return np.array([self.gm])

    @property
    def primaries(self) -> tuple[Body, ...]:
        """The central body at the origin, all of the system's mass (an impact body when its
        radius is positive)."""
        return (Body("Central body", np.zeros(3), float(units.km_to_lu(self.body_radius_km)), 1.0),)

    def kepler(self, states: np.ndarray, dt) -> np.ndarray:
        """Closed-form propagation of states (N, 6) [LU, VU] by ``dt`` TU -> (N, 6)."""
        return kepler_propagate(self._check_states(states), dt, self.gm)


@hookimpl
def cistrack_register(registry):
    registry.add("dynamics", "twobody", TwoBody)
