"""Single-shooting differential corrector for CR3BP periodic orbits symmetric about the xz-plane.

A periodic orbit that crosses the xz-plane (y = 0) perpendicularly twice per period starts at
(x0, 0, z0, 0, vy0, 0) and reaches, half a period later, another perpendicular crossing where
vx = vz = 0. Starting from a guess, the corrector integrates the state together with its 6x6
state-transition matrix (STM) to the chosen y = 0 crossing and applies Newton's method to the
free initial coordinates (two of x0, z0, vy0; for planar orbits one of x0, vy0) so that
vx and vz vanish there, accounting for the shift of the crossing time:

    d(g)/d(X0) = Phi[g, X0] - (dg/dt) / vy_f * Phi[y, X0],   g in {vx, vz}.

Integration: scipy DOP853 at rtol 1e-13 on the numba right-hand side (42 equations); the crossing
is located on the dense output. Example::

    from cistrack.plugins.dynamics.corrector import correct_symmetric_orbit
    orb = correct_symmetric_orbit([1.0221, 0, -0.1821, 0, -0.1033, 0], fixed="x", period_guess=1.51)
    orb.state, orb.period
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from cistrack.errors import CistrackError

from cistrack.astro.primaries import MU_EARTH_MOON

from .cr3bp_variational import cr3bp_variational_rhs
from .cr3bp import cr3bp_rhs as _lazy_cr3bp_rhs

cr3bp_rhs = _lazy_cr3bp_rhs.dispatcher  # compiled code below calls the numba function itself

__all__ = ["CorrectionError", "CorrectedOrbit", "CorrectorSettings", "correct_symmetric_orbit", "propagate_with_stm",
           "cr3bp_stm_rhs"]


class CorrectionError(CistrackError, RuntimeError):
    """The differential corrector did not converge (or found no crossing to target)."""


@dataclass(frozen=True)
class CorrectedOrbit:
    """Result of :func:`correct_symmetric_orbit`.

    state : (6,) float   corrected initial state (x0, 0, z0, 0, vy0, 0), LU and VU
    period : float       full period, TU (twice the time of the targeted crossing)
    iterations : int     Newton iterations used
    residual : float     max(|vx|, |vz|) at the half-period crossing, VU
    """

    state: np.ndarray
    period: float
    iterations: int
    residual: float


cr3bp_stm_rhs = cr3bp_variational_rhs
"""CR3BP state + STM on 42 components (the variational equations of :mod:`.cr3bp_variational`,
shared with ``CR3BP.propagate_with_stm``)."""


def _fun(mu: float):
    params = np.array([mu])

    def f(t, y):
        out = np.empty(42)
        cr3bp_stm_rhs(t, y, params, out)
        return out
    return f


def propagate_with_stm(state, t: float, mu: float = MU_EARTH_MOON, rtol: float = 1e-13,
                       atol: float = 1e-14) -> tuple[np.ndarray, np.ndarray]:
    """State (6,) and STM (6, 6) after ``t`` TU (scipy DOP853 at tight tolerance)."""
    y0 = np.concatenate([np.asarray(state, dtype=float), np.eye(6).ravel()])
    sol = solve_ivp(_fun(mu), (0.0, float(t)), y0, method="DOP853", rtol=rtol, atol=atol)
    return sol.y[:6, -1], sol.y[6:, -1].reshape(6, 6)


def _crossing(x0: np.ndarray, mu: float, half_guess: float | None, crossing: int | None,
              rtol: float, atol: float):
    """State+STM (42,) and time at the targeted y = 0 crossing after t = 0."""
    f = _fun(mu)

    def event(t, y):
        return y[1]

    y0 = np.concatenate([x0, np.eye(6).ravel()])
    if half_guess is not None:
        t_end = 1.6 * half_guess
    else:
        t_end = 50.0
    want = crossing if crossing is not None else None
    if want is not None:
        event.terminal = want + 1  # stop once we have the one we want (plus the start)
    sol = solve_ivp(f, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol, events=event)
    times = sol.t_events[0]
    ys = sol.y_events[0]
    keep = times > 1e-9
    times, ys = times[keep], ys[keep]
    if times.size == 0:
        raise CorrectionError("differential corrector: the trajectory does not cross y = 0 "
                              f"within {t_end:g} TU of the guess")
    if want is not None:
        if times.size < want:
            raise CorrectionError(f"differential corrector: only {times.size} crossing(s) of y = 0, "
                                  f"crossing={want} requested")
        i = want - 1
    elif half_guess is not None:
        i = int(np.argmin(np.abs(times - half_guess)))
    else:
        i = 0
    return times[i], ys[i]


@dataclass(frozen=True)
class CorrectorSettings:
    """Numerical settings of :func:`correct_symmetric_orbit`.

    tol : float        convergence threshold on max(|vx|, |vz|) at the crossing, VU
    max_iter : int     Newton iterations at most
    rtol, atol : float DOP853 tolerances of the state + STM integration
    """

    tol: float = 1e-12
    max_iter: int = 30
    rtol: float = 1e-13
    atol: float = 1e-14


def _symmetric_start(guess) -> np.ndarray:
    """The guess (6,) as a float copy with y0, vx0 and vz0 set to 0."""
    x = np.array(guess, dtype=float).reshape(-1)
    if x.shape != (6,) or not np.all(np.isfinite(x)):
        raise CorrectionError(f"differential corrector: guess must be 6 finite numbers, got {guess!r}")
    x[[1, 3, 5]] = 0.0
    return x


def _free_and_targets(planar: bool, fixed: str) -> tuple[list[int], list[int]]:
    """Indices of the corrected initial coordinates and of the velocities driven to 0."""
    if fixed not in ("x", "z", "vy"):
        raise CorrectionError(f"differential corrector: fixed must be 'x', 'z' or 'vy', got {fixed!r}")
    if planar and fixed == "z":
        raise CorrectionError("differential corrector: a planar guess (z0 = 0) needs fixed='x' or 'vy'")
    coord = {"x": 0, "z": 2, "vy": 4}
    candidates = [0, 4] if planar else [0, 2, 4]
    free = [i for i in candidates if i != coord[fixed]]
    targets = [3] if planar else [3, 5]
    return free, targets


def _newton_step(tc: float, yc: np.ndarray, mu: float, free: list[int], targets: list[int]) -> np.ndarray:
    """Change of the free initial coordinates that zeroes the target velocities at the crossing
    (state + STM ``yc`` (42,) at time ``tc``), the crossing's time shift included."""
    phi = yc[6:].reshape(6, 6)
    fdot = np.empty(6)
    cr3bp_rhs(tc, np.ascontiguousarray(yc[:6]), np.array([mu]), fdot)
    jac = phi[np.ix_(targets, free)] - np.outer(fdot[targets] / yc[4], phi[1, free])
    return np.linalg.lstsq(jac, -yc[targets], rcond=None)[0]


def correct_symmetric_orbit(guess, mu: float = MU_EARTH_MOON, *, fixed: str = "x",
                            period_guess: float | None = None, crossing: int | None = None,
                            **settings) -> CorrectedOrbit:
    """Correct a guess of a periodic orbit symmetric about the xz-plane.

    Parameters
    ----------
    guess : (6,) float
        (x0, y0, z0, vx0, vy0, vz0) in LU and VU; y0, vx0 and vz0 are set to 0.
    mu : float
        Mass ratio.
    fixed : {"x", "z", "vy"}
        The initial coordinate held fixed ("z" only for spatial orbits; for planar orbits,
        z0 = 0, one of x0/vy0 is held and the other corrected).
    period_guess : float, optional
        Approximate period (TU): the y = 0 crossing nearest half of it is targeted.
    crossing : int, optional
        Target the n-th crossing of y = 0 instead (1 = the first after t = 0).
    **settings
        Fields of :class:`CorrectorSettings`: tol (1e-12, convergence threshold on
        max(|vx|, |vz|) at the crossing, VU), max_iter (30), rtol (1e-13), atol (1e-14).

    Returns
    -------
    CorrectedOrbit. Raises :class:`CorrectionError` if Newton's method does not reach ``tol``
    within ``max_iter`` iterations or the trajectory never crosses y = 0.
    """
    opts = CorrectorSettings(**settings)
    x = _symmetric_start(guess)
    free, targets = _free_and_targets(x[2] == 0.0, fixed)
    half = None if period_guess is None else 0.5 * float(period_guess)
    residual = np.inf
    for it in range(opts.max_iter + 1):
        tc, yc = _crossing(x, mu, half, crossing, opts.rtol, opts.atol)
        residual = float(np.max(np.abs(yc[targets])))
        if residual <= opts.tol:
            return CorrectedOrbit(state=x.copy(), period=2.0 * tc, iterations=it, residual=residual)
        if it == opts.max_iter:
            break
        x[free] += _newton_step(tc, yc, mu, free, targets)
        if not np.all(np.isfinite(x)):
            break
        half = tc  # follow the crossing we are converging on
    raise CorrectionError(f"differential corrector did not converge: residual {residual:.3e} VU after "
                          f"{opts.max_iter} iterations (tol {opts.tol:g}); try a better guess, another 'fixed' "
                          "coordinate, or period_guess/crossing to target the right crossing")
