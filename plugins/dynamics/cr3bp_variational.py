"""Variational equations of the CR3BP, for state transition matrices on the compiled integrator.

``cr3bp_variational_rhs(t, y, p, out)`` on 42 components: y[0:6] the synodic state (LU, VU),
y[6:42] the STM Phi (6x6, row-major); p = [mu]. out[0:6] are the equations of motion of
:mod:`.cr3bp` and out[6:42] = A Phi with

    A = [[0, I], [U, 2 Omega]],   U = d(a_gravity + centrifugal)/d r (symmetric),
    2 Omega = [[0, 2, 0], [-2, 0, 0], [0, 0, 0]]  (Coriolis),

with a = (1-mu)/r1^3, b = mu/r2^3, xe = x + mu, xm = x - 1 + mu, e = (xe, y, z), m = (xm, y, z):
U = diag(1, 1, 0) - (a + b) I + 3 a e e^T / r1^2 + 3 b m m^T / r2^2.

Self-contained (it does not call :func:`.cr3bp.cr3bp_rhs`): :mod:`.cr3bp` imports this module on
the first ``propagate_with_stm`` call, and a module it imports must not import it back.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import lazy_njit

__all__ = ["cr3bp_variational_rhs"]


# no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
@lazy_njit(cache=True)
def cr3bp_variational_rhs(t, y, p, out):
    """CR3BP state + STM: y (42,) = state (6) then Phi (6x6 row-major) -> out (42,); p = [mu]."""
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
    a = (1.0 - mu) / (r1s * np.sqrt(r1s))
    b = mu / (r2s * np.sqrt(r2s))
    out[0] = vx
    out[1] = vy
    out[2] = y[5]
    out[3] = x + 2.0 * vy - a * xe - b * xm
    out[4] = yy - 2.0 * vx - (a + b) * yy
    out[5] = -(a + b) * z
    a3 = 3.0 * a / r1s
    b3 = 3.0 * b / r2s
    uxx = 1.0 - a - b + a3 * xe * xe + b3 * xm * xm
    uyy = 1.0 - a - b + (a3 + b3) * yy * yy
    uzz = -a - b + (a3 + b3) * z * z
    uxy = (a3 * xe + b3 * xm) * yy
    uxz = (a3 * xe + b3 * xm) * z
    uyz = (a3 + b3) * yy * z
    for c in range(6):
        p0 = y[6 + c]
        p1 = y[12 + c]
        p2 = y[18 + c]
        p3 = y[24 + c]
        p4 = y[30 + c]
        out[6 + c] = p3
        out[12 + c] = p4
        out[18 + c] = y[36 + c]
        out[24 + c] = uxx * p0 + uxy * p1 + uxz * p2 + 2.0 * p4
        out[30 + c] = uxy * p0 + uyy * p1 + uyz * p2 - 2.0 * p3
        out[36 + c] = uxz * p0 + uyz * p1 + uzz * p2
