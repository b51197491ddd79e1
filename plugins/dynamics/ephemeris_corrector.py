"""CR3BP catalog orbits carried into the ephemeris model, and a multiple-shooting corrector.

A catalog orbit (:mod:`.orbit_catalog`, CR3BP synodic) is propagated in the CR3BP over the wanted
number of revolutions and sampled at patch points (``nodes_per_rev`` equally spaced in time per
revolution, half a spacing off the catalog state so that none sits at an NRHO's perilune). Each patch point is placed in the real Earth-Moon
frame with the *pulsating* scaling (:meth:`cistrack.astro.earth_moon.EarthMoonFrame.pulsating_to_gcrs`:
Earth and Moon where the CR3BP has them) at the time when the real frame has turned by the same
angle as the CR3BP's (:func:`synodic_angle_times`).

The corrector then removes the velocity and position jumps between consecutive arcs of the
ephemeris model: with X = (x_0, ..., x_{M-1}) the patch states (geocentric GCRS, LU and VU) at
fixed times t_k and F_k(X) = phi(x_k; t_k -> t_{k+1}) - x_{k+1}, Newton steps of minimum norm
dX = -J^T (J J^T)^-1 F (J: state transition matrices by central finite differences of the compiled
integrator, and -I) until every jump is below ``tol`` (default 1e-10 LU = 4 cm and 1e-10 VU =
0.1 mm/s). The result is one continuous ephemeris trajectory that follows the catalog orbit's
shape over all the revolutions.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from cistrack import units
from cistrack.errors import PropagationError
from cistrack.propagation import CompiledDynamics

from .cr3bp import CR3BP
from .ephemeris import EphemerisDynamics

__all__ = ["PatchedOrbit", "catalog_patch_points", "correct_multiple_shooting"]


@dataclass
class PatchedOrbit:
    """Patch points of a trajectory in the ephemeris model.

    Attributes
    ----------
    times : (M,) float       TU after the model's epoch
    states : (M, 6) float    geocentric GCRS states at ``times``, LU and VU (the kernel's frame)
    jumps : (M-1,) float     largest |position or velocity| mismatch at each junction, LU / VU
    iterations : int         Newton iterations taken (0 for an uncorrected guess)
    """

    times: np.ndarray
    states: np.ndarray
    jumps: np.ndarray
    iterations: int = 0

    def synodic(self, dyn: EphemerisDynamics) -> np.ndarray:
        """The patch states in the real rotating frame (M, 6) [LU, VU]."""
        return np.array([dyn.from_inertial(s[None], t)[0] for s, t in zip(self.states, self.times)])


def catalog_patch_points(dyn: EphemerisDynamics, state: np.ndarray, period: float,
                         revolutions: int, nodes_per_rev: int = 8, t0: float = 0.0,
                         offset: float = 0.5, cr3bp: CompiledDynamics | None = None) -> PatchedOrbit:
    """Initial guess: a CR3BP orbit's states at patch times, placed in the ephemeris model.

    Parameters
    ----------
    dyn : EphemerisDynamics
        The model (its epoch fixes where the Moon is).
    state : (6,) float
        CR3BP synodic state of the catalog orbit [LU, VU].
    period : float
        Its CR3BP period, TU.
    revolutions, nodes_per_rev : int
        Span and density of the patch points.
    t0 : float
        TU after the epoch at which the real frame's angle matches the catalog state's.
    offset : float
        Patch points sit at (k + offset) period / nodes_per_rev after the catalog state; the
        default 0.5 keeps them off the catalog state's apse and its opposite (for an NRHO, off
        perilune, where a small phase error is a large velocity error).
    cr3bp : CompiledDynamics, optional
        The CR3BP model to sample the orbit with (default: :class:`.cr3bp.CR3BP`).
    """
    if cr3bp is None:
        cr3bp = CR3BP()
    n = int(revolutions) * int(nodes_per_rev)
    tau = (np.arange(n + 1) + float(offset)) * (period / nodes_per_rev)
    cr = cr3bp.propagate(np.asarray(state, float)[None], 0.0, tau).states[:, 0]
    times = synodic_angle_times(dyn, t0, tau)
    gcrs = np.array([dyn.frame.pulsating_to_gcrs(s, t) for s, t in zip(cr, times)])
    states = units.state_from_km(gcrs)
    return PatchedOrbit(times=times, states=states, jumps=_jumps(_without_impacts(dyn), times, states)[1])


def synodic_angle_times(dyn: EphemerisDynamics, t0: float, tau: np.ndarray) -> np.ndarray:
    """Model times (TU) at which the real frame has turned by ``tau`` radians since ``t0``.

    CR3BP time is the synodic angle (TU = 1/n); the real Moon turns at h/d^2, faster near
    perigee. Matching the angle, not the clock, keeps a CR3BP orbit's phase with the Moon.
    """
    tau = np.asarray(tau, dtype=float)
    span = float(tau.max()) * 1.3 + 0.5
    grid = t0 + np.linspace(0.0, span, int(span * 200) + 2)
    rate = dyn.frame.axes(grid).angular_rate * units.TU_S  # rad per TU
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(grid))])
    return np.interp(tau, angle, grid)


def _without_impacts(dyn: EphemerisDynamics) -> EphemerisDynamics:
    """A copy of ``dyn`` whose bodies have no surfaces (iterates may cross the Moon's sphere)."""
    free = copy.copy(dyn)
    free.earth_radius_km = 0.0
    free.moon_radius_km = 0.0
    free._params_cache = None
    return free


def _arcs(dyn: EphemerisDynamics, times: np.ndarray, states: np.ndarray, rtol: float) -> np.ndarray:
    """End state of each arc k: states[k] propagated from times[k] to times[k+1], (M-1, 6)."""
    out = np.empty((len(times) - 1, 6))
    for k in range(len(times) - 1):
        p = dyn.propagate_inertial(states[k][None], times[k], times[k + 1], rtol=rtol, atol=rtol)
        if not p.alive[0]:
            raise PropagationError(f"multiple shooting: arc {k} (t = {times[k]:.4f} TU) hits a body")
        out[k] = p.final[0]
    return out


def _jumps(dyn, times, states, rtol: float = 1e-13) -> tuple[np.ndarray, np.ndarray]:
    ends = _arcs(dyn, times, states, rtol)
    defect = ends - states[1:]
    return defect, np.max(np.abs(defect), axis=1)


def _stm(dyn: EphemerisDynamics, t_a: float, t_b: float, x: np.ndarray, step: float,
         rtol: float) -> np.ndarray:
    """State transition matrix (6, 6) of one arc by central differences (one batched call)."""
    pert = np.repeat(x[None], 12, axis=0)
    for j in range(6):
        pert[2 * j, j] += step
        pert[2 * j + 1, j] -= step
    p = dyn.propagate_inertial(pert, t_a, t_b, rtol=rtol, atol=rtol)
    end = p.final
    return np.stack([(end[2 * j] - end[2 * j + 1]) / (2.0 * step) for j in range(6)], axis=1)


def correct_multiple_shooting(dyn: EphemerisDynamics, guess: PatchedOrbit, tol: float = 1e-10,
                              max_iter: int = 25, step: float = 1e-7, rtol: float = 1e-13) -> PatchedOrbit:
    """Make the patched trajectory continuous in the ephemeris model (minimum-norm Newton).

    Returns a new :class:`PatchedOrbit` whose junction jumps are all below ``tol`` (LU, VU).
    Iterates are propagated without impact surfaces (an early iterate may pass through the
    Moon's sphere); the converged orbit is checked with them. Each Newton step is halved until
    the defect norm decreases. Raises :class:`cistrack.errors.PropagationError` if the converged
    orbit hits a body or the iteration does not converge within ``max_iter``.
    """
    model = dyn
    dyn = _without_impacts(model)
    times = np.asarray(guess.times, float)
    x = np.array(guess.states, dtype=float, copy=True)
    m = len(times)
    defect, jumps = _jumps(dyn, times, x, rtol)
    for it in range(max_iter + 1):
        if np.max(jumps) < tol:
            _arcs(model, times, x, rtol)  # the converged orbit must clear the Earth and the Moon
            return PatchedOrbit(times=times, states=x, jumps=jumps, iterations=it)
        if it == max_iter:
            break
        jac = np.zeros((6 * (m - 1), 6 * m))
        for k in range(m - 1):
            jac[6 * k:6 * k + 6, 6 * k:6 * k + 6] = _stm(dyn, times[k], times[k + 1], x[k], step, rtol)
            jac[6 * k:6 * k + 6, 6 * k + 6:6 * k + 12] = -np.eye(6)
        dx = (-jac.T @ np.linalg.solve(jac @ jac.T, defect.reshape(-1))).reshape(m, 6)
        # backtracking: a full Newton step far from the solution can throw an arc into the Moon
        lam = 1.0
        norm0 = np.linalg.norm(defect)
        while True:
            trial = x + lam * dx
            try:
                d_new, j_new = _jumps(dyn, times, trial, rtol)
                if np.linalg.norm(d_new) < norm0 or lam < 1e-3:
                    break
            except PropagationError:
                if lam < 1e-3:
                    raise
            lam *= 0.5
        x, defect, jumps = trial, d_new, j_new
    raise PropagationError(f"multiple shooting did not converge in {max_iter} iterations "
                           f"(largest jump {np.max(jumps):.3g} LU/VU, wanted < {tol:g})")


def correct_catalog_orbit(dyn: EphemerisDynamics, state: np.ndarray, period: float,
                          revolutions: int, nodes_per_rev: int = 8, first: int = 4,
                          tol: float = 1e-10, t0: float = 0.0) -> PatchedOrbit:
    """A catalog orbit made continuous in the ephemeris model over ``revolutions``, by
    continuation: correct the first ``first`` revolutions from the CR3BP guess, then append the
    next revolution's CR3BP patch points and correct the whole again, until all are done
    (measured on the 9:2 NRHO at 2026-01-01: all ten revolutions at once stall in damped Newton
    steps; four, then one more at a time, converge in 5-10 iterations each).

    ``state`` (6,) and ``period`` (TU) are the CR3BP catalog orbit's; the result's patch points
    are geocentric GCRS (LU, VU) at TU after the model's epoch.
    """
    guess = catalog_patch_points(dyn, state, period, revolutions, nodes_per_rev, t0)
    n = min(int(first), int(revolutions)) * nodes_per_rev + 1
    sol = correct_multiple_shooting(dyn, PatchedOrbit(guess.times[:n], guess.states[:n], guess.jumps[:n - 1]), tol=tol)
    while n < len(guess.times):
        n_next = min(n + nodes_per_rev, len(guess.times))
        states = np.concatenate([sol.states, guess.states[n:n_next]])
        trial = PatchedOrbit(guess.times[:n_next], states, np.zeros(n_next - 1))
        sol = correct_multiple_shooting(dyn, trial, tol=tol)
        n = n_next
    return sol
