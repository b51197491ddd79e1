"""Earth–Moon circular restricted three-body problem (CR3BP), registered as dynamics "cr3bp".

Rotating (synodic) barycentric frame, nondimensional: LU = Earth–Moon distance, TU = 1/n.
Earth at (-mu, 0, 0), Moon at (1 - mu, 0, 0). With r1 = |(x+mu, y, z)|, r2 = |(x-1+mu, y, z)|:

    ax = x + 2 vy - (1-mu)(x+mu)/r1^3 - mu (x-1+mu)/r2^3
    ay = y - 2 vx - (1-mu) y/r1^3     - mu y/r2^3
    az =          - (1-mu) z/r1^3     - mu z/r2^3

(the paper prints the z equation with a sign typo; this one is right). The Jacobi constant
C = x^2 + y^2 + 2(1-mu)/r1 + 2 mu/r2 - |v|^2 is conserved.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_int, check_positive, check_range
from cistrack.api import hookimpl
from cistrack.lazy import lazy_njit
from cistrack.interfaces.dynamics import Body
from cistrack.astro.primaries import EARTH_RADIUS_KM, MOON_RADIUS_KM, MU_EARTH_MOON, earth_moon_primaries
from cistrack.propagation import CompiledDynamics

__all__ = ["CR3BP", "cr3bp_rhs", "jacobi_constant", "MU_EARTH_MOON"]


# compiled on first use (or inlined into the propagation kernels): listing plugins needs no numba
# no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
@lazy_njit(cache=True)
def cr3bp_rhs(t, y, p, out):
    """CR3BP equations of motion: y (6,) [LU, VU] -> out (6,) [VU, VU/TU]; p = [mu]."""
    mu = p[0]
    x = y[0]
    yy = y[1]
    z = y[2]
    vx = y[3]
    vy = y[4]
    xe = x + mu
    xm = x - 1.0 + mu
    yz2 = yy * yy + z * z
    r1s = xe * xe + yz2
    r2s = xm * xm + yz2
    c1 = (1.0 - mu) / (r1s * np.sqrt(r1s))
    c2 = mu / (r2s * np.sqrt(r2s))
    cs = c1 + c2
    out[0] = vx
    out[1] = vy
    out[2] = y[5]
    out[3] = x + 2.0 * vy - c1 * xe - c2 * xm
    out[4] = yy - 2.0 * vx - cs * yy
    out[5] = -cs * z


def jacobi_constant(states: np.ndarray, mu: float = MU_EARTH_MOON) -> np.ndarray:
    """Jacobi constant of synodic states (N, 6) [LU, VU] -> (N,) [VU^2]."""
    s = np.asarray(states, dtype=float).reshape(-1, 6)
    x, y, z = s[:, 0], s[:, 1], s[:, 2]
    r1 = np.sqrt((x + mu) ** 2 + y * y + z * z)
    r2 = np.sqrt((x - 1.0 + mu) ** 2 + y * y + z * z)
    v2 = np.sum(s[:, 3:] ** 2, axis=1)
    return x * x + y * y + 2.0 * (1.0 - mu) / r1 + 2.0 * mu / r2 - v2


class CR3BP(CompiledDynamics):
    """Earth–Moon CR3BP with per-particle adaptive DOP853 propagation and Earth/Moon impacts.

    Parameters
    ----------
    mu : float
        Mass ratio m2 / (m1 + m2), in (0, 0.5].
    rtol, atol : float
        Per-particle relative / absolute integration tolerances (nondimensional). The defaults
        give <= 1e-9 LU position error after one 9:2 NRHO period.
    earth_radius_km, moon_radius_km : float
        Impact radii, km (0 disables impacts on that body).
    max_steps : int
        Step limit per particle and call.
    """

    rhs = cr3bp_rhs

    def __init__(self, mu: float = MU_EARTH_MOON, rtol: float = 1e-12, atol: float = 2e-11,
                 earth_radius_km: float = EARTH_RADIUS_KM, moon_radius_km: float = MOON_RADIUS_KM,
                 max_steps: int = 5_000_000):
        self.mu = check_range(self, "mu", mu, 0.0, 0.5, lo_open=True)
        self.rtol = check_range(self, "rtol", rtol, 1e-15, 1e-2)
        self.atol = check_range(self, "atol", atol, 1e-18, 1e-2)
        self.earth_radius_km = check_range(self, "earth_radius_km", earth_radius_km, 0.0, 1e5)
        self.moon_radius_km = check_range(self, "moon_radius_km", moon_radius_km, 0.0, 1e5)
        self.max_steps = check_int(self, "max_steps", max_steps, minimum=1)
        check_positive(self, "rtol", rtol)

    def params_vector(self) -> np.ndarray:
        return np.array([self.mu])

    @property
    def primaries(self) -> tuple[Body, ...]:
        """Earth at (-mu, 0, 0) and Moon at (1-mu, 0, 0), mass fractions 1-mu and mu, radii in LU
        (the impact bodies are those with a positive radius)."""
        return earth_moon_primaries(self.mu, self.earth_radius_km, self.moon_radius_km)

    def propagate_with_stm(self, state: np.ndarray, t0: float, times) -> tuple[np.ndarray, np.ndarray]:
        """State (6,) and state transition matrix from ``t0`` to ``times`` (K,) TU -> (states
        (K, 6), stms (K, 6, 6)): the variational equations (:mod:`.cr3bp_variational`)
        integrated with the state by the compiled DOP853
        (:func:`cistrack.propagation.variational.propagate_variational`) at the model's
        tolerances. Raises ``PropagationError`` when the trajectory hits a body."""
        from cistrack.propagation.variational import propagate_variational

        from .cr3bp_variational import cr3bp_variational_rhs

        return propagate_variational(self, cr3bp_variational_rhs, state, t0, times)

    def jacobi(self, states: np.ndarray) -> np.ndarray:
        """Jacobi constant of states (N, 6) [LU, VU] -> (N,) [VU^2]."""
        return jacobi_constant(self._check_states(states), self.mu)


@hookimpl
def cistrack_register(registry):
    registry.add("dynamics", "cr3bp", CR3BP)
