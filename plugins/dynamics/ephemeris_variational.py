"""Variational equations of the ephemeris model (geocentric GCRS, LU, VU, TU).

``ephemeris_stm_rhs(t, y, p, out)`` on 42 components: y[0:6] the kernel state, y[6:42] the state
transition matrix Phi (6x6, row-major); out[0:6] is :func:`.ephemeris_rhs.ephemeris_rhs` and
out[6:42] = A Phi with A = [[0, I], [G, 0]], G = d a / d r the gravity gradient (3x3, symmetric):

- a point mass GM at b (Earth at the origin: b = 0, sign of the attraction included), with
  d = b - r: d a / d r = -GM (I / |d|^3 - 3 d d^T / |d|^5); the indirect terms do not depend on r;
- the cannonball radiation pressure c u/|u|^3 (u = s - r, c = -P AU^2) is the same form with
  GM replaced by c;
- Earth J2, a = C w with C = -(3/2) J2 GM_E R_E^2 / |r|^5, w = q r + 2 (r.k) k,
  q = 1 - 5 (r.k)^2/|r|^2:
  d a / d r = -5 C w r^T / |r|^2 + C (r (dq/dr)^T + q I + 2 k k^T),
  dq/dr = -10 (r.k) k / |r|^2 + 10 (r.k)^2 r / |r|^4.

The parameter vector is the model's (:func:`.ephemeris_rhs.pack_params`).

:func:`synodic_stm` integrates them with the state and carries the STM into the real rotating
frame: the synodic <-> GCRS change is affine in the state at each time, so the synodic STM is
B(t_k) Phi A(t0) with A, B the linear parts of ``to_inertial`` at t0 and ``from_inertial`` at t_k
(taken as differences of the maps at the unit vectors, exact for affine maps).

This module compiles numba functions when imported: the model imports it on the first
``propagate_with_stm`` call.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from cistrack.interfaces.transition_matrix import check_stm_request
from cistrack.propagation.variational import propagate_variational_with

from .ephemeris_rhs import AU, EARTH_SHARE, GM_E, GM_M, GM_S, J2, KX, KY, KZ, P_SRP, R_E
from .ephemeris_rhs import bodies_position as _lazy_bodies_position
from .ephemeris_rhs import ephemeris_rhs as _lazy_ephemeris_rhs

__all__ = ["ephemeris_stm_rhs", "ephemeris_stm_srp_rhs", "synodic_stm", "synodic_srp_sensitivity"]

_bodies_position = _lazy_bodies_position.dispatcher  # compiled code calls the numba functions themselves
_ephemeris_rhs = _lazy_ephemeris_rhs.dispatcher


@njit(cache=True)  # no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
def _gravity_gradient(t, y, p):
    """G = d a / d r at the kernel state y[0:3] (its six distinct entries gxx, gyy, gzz, gxy, gxz,
    gyz), then the Moon's and the Sun's positions (mx, my, mz, sx, sy, sz) at ``t``."""
    mx, my, mz, sx, sy, sz = _bodies_position(p, t)
    x = y[0]
    yy = y[1]
    z = y[2]
    # Earth
    r2 = x * x + yy * yy + z * z
    r1 = np.sqrt(r2)
    c = p[GM_E] / (r2 * r1)
    c5 = 3.0 * c / r2
    gxx = -c + c5 * x * x
    gyy = -c + c5 * yy * yy
    gzz = -c + c5 * z * z
    gxy = c5 * x * yy
    gxz = c5 * x * z
    gyz = c5 * yy * z
    # Moon (direct term)
    dx = mx - x
    dy = my - yy
    dz = mz - z
    d2 = dx * dx + dy * dy + dz * dz
    c = p[GM_M] / (d2 * np.sqrt(d2))
    c5 = 3.0 * c / d2
    gxx += -c + c5 * dx * dx
    gyy += -c + c5 * dy * dy
    gzz += -c + c5 * dz * dz
    gxy += c5 * dx * dy
    gxz += c5 * dx * dz
    gyz += c5 * dy * dz
    # Sun (direct term) and radiation pressure, both along u = s - r
    gm_u = p[GM_S] - p[P_SRP] * p[AU] * p[AU]
    if p[GM_S] != 0.0 or p[P_SRP] != 0.0:
        f = p[EARTH_SHARE]
        ux = sx + f * mx - x
        uy = sy + f * my - yy
        uz = sz + f * mz - z
        u2 = ux * ux + uy * uy + uz * uz
        c = gm_u / (u2 * np.sqrt(u2))
        c5 = 3.0 * c / u2
        gxx += -c + c5 * ux * ux
        gyy += -c + c5 * uy * uy
        gzz += -c + c5 * uz * uz
        gxy += c5 * ux * uy
        gxz += c5 * ux * uz
        gyz += c5 * uy * uz
    if p[J2] != 0.0:
        kx = p[KX]
        ky = p[KY]
        kz = p[KZ]
        rk = x * kx + yy * ky + z * kz
        cj = -1.5 * p[J2] * p[GM_E] * p[R_E] * p[R_E] / (r2 * r2 * r1)
        q = 1.0 - 5.0 * rk * rk / r2
        wx = q * x + 2.0 * rk * kx
        wy = q * yy + 2.0 * rk * ky
        wz = q * z + 2.0 * rk * kz
        e = -5.0 * cj / r2
        qk = -10.0 * rk / r2            # dq/dr = qk k + qr r
        qr = 10.0 * rk * rk / (r2 * r2)
        # C r (dq/dr)^T = C (qk r k^T + qr r r^T); symmetric in total with the w r^T term
        gxx += e * wx * x + cj * (x * (qk * kx + qr * x) + q + 2.0 * kx * kx)
        gyy += e * wy * yy + cj * (yy * (qk * ky + qr * yy) + q + 2.0 * ky * ky)
        gzz += e * wz * z + cj * (z * (qk * kz + qr * z) + q + 2.0 * kz * kz)
        gxy += e * wx * yy + cj * (x * (qk * ky + qr * yy) + 2.0 * kx * ky)
        gxz += e * wx * z + cj * (x * (qk * kz + qr * z) + 2.0 * kx * kz)
        gyz += e * wy * z + cj * (yy * (qk * kz + qr * z) + 2.0 * ky * kz)
    return gxx, gyy, gzz, gxy, gxz, gyz, mx, my, mz, sx, sy, sz


@njit(cache=True)  # no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
def ephemeris_stm_rhs(t, y, p, out):
    """State + STM derivative: y (42,) = state (6) then Phi (6x6 row-major) -> out (42,)."""
    _ephemeris_rhs(t, y, p, out)
    gxx, gyy, gzz, gxy, gxz, gyz, _, _, _, _, _, _ = _gravity_gradient(t, y, p)
    _stm_columns(y, out, gxx, gyy, gzz, gxy, gxz, gyz)


@njit(cache=True)  # no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
def _stm_columns(y, out, gxx, gyy, gzz, gxy, gxz, gyz):
    """out[6:42] = A Phi, A = [[0, I], [G, 0]], Phi = y[6:42] row-major."""
    for col in range(6):
        p0 = y[6 + col]
        p1 = y[12 + col]
        p2 = y[18 + col]
        out[6 + col] = y[24 + col]
        out[12 + col] = y[30 + col]
        out[18 + col] = y[36 + col]
        out[24 + col] = gxx * p0 + gxy * p1 + gxz * p2
        out[30 + col] = gxy * p0 + gyy * p1 + gyz * p2
        out[36 + col] = gxz * p0 + gyz * p1 + gzz * p2


@njit(cache=True)  # no fast-math: bit-reproducible (cistrack.propagation.dop853_source.DEFAULT_FASTMATH)
def ephemeris_stm_srp_rhs(t, y, p, out):
    """State + STM + radiation-pressure sensitivity: y (48,) = state, Phi (6x6 row-major), then
    s = d x / d P (6,), P the pressure coefficient ``p[P_SRP]`` -> out (48,): as
    :func:`ephemeris_stm_rhs`, and ds/dt = A s + [0; d a / d P], d a / d P = -AU^2 u / |u|^3
    (u = Sun - r: the radiation pressure is linear in P)."""
    _ephemeris_rhs(t, y, p, out)
    gxx, gyy, gzz, gxy, gxz, gyz, mx, my, mz, sx, sy, sz = _gravity_gradient(t, y, p)
    _stm_columns(y, out, gxx, gyy, gzz, gxy, gxz, gyz)
    f = p[EARTH_SHARE]
    ux = sx + f * mx - y[0]
    uy = sy + f * my - y[1]
    uz = sz + f * mz - y[2]
    u2 = ux * ux + uy * uy + uz * uz
    c = -p[AU] * p[AU] / (u2 * np.sqrt(u2))
    s0 = y[42]
    s1 = y[43]
    s2 = y[44]
    out[42] = y[45]
    out[43] = y[46]
    out[44] = y[47]
    out[45] = gxx * s0 + gxy * s1 + gxz * s2 + c * ux
    out[46] = gxy * s0 + gyy * s1 + gyz * s2 + c * uy
    out[47] = gxz * s0 + gyz * s1 + gzz * s2 + c * uz


def synodic_stm(dyn: Any, state: Any, t0: float, times: Any) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) and STMs (K, 6, 6) in the real rotating frame (LU, VU) of a synodic ``state``
    (6,) propagated by the ephemeris model ``dyn`` from ``t0`` to ``times`` (K,) TU."""
    states, stms, _ = _synodic(dyn, ephemeris_stm_rhs, 0, state, t0, times)
    return states, stms


def synodic_srp_sensitivity(dyn: Any, state: Any, t0: float,
                            times: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`synodic_stm`, and d x(t_k) / d P (K, 6) in the real rotating frame (LU, VU per
    unit of the kernel's pressure coefficient ``P_SRP``, LU^3 / TU^2 per AU^2), the state at
    ``t0`` held: the variational equations of :func:`ephemeris_stm_srp_rhs`."""
    return _synodic(dyn, ephemeris_stm_srp_rhs, 6, state, t0, times)


def _synodic(dyn: Any, rhs: Any, extra: int, state: Any, t0: float,
             times: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(states, STMs, extras (K, extra)) of ``rhs`` integrated in GCRS, carried into the real
    rotating frame: states by the map, STMs by B(t_k) Phi A(t0), the extras (sensitivities of the
    GCRS state to a parameter, zero at ``t0``) by B(t_k)."""
    x, t0, t_out = check_stm_request(dyn._label(), state, t0, times)
    span = np.concatenate(([t0], t_out))
    dyn._ensure_window(float(span.min()), float(span.max()))
    basis = np.vstack([np.zeros(6), np.eye(6)])                      # (7, 6): origin, unit vectors
    to_in = dyn.to_inertial(basis, t0)
    a0 = (to_in[1:] - to_in[0]).T                                    # d gcrs / d synodic at t0
    s_in, phi_in, e_in = propagate_variational_with(dyn, rhs, dyn.to_inertial(x[None], t0)[0], t0, t_out, extra)
    k = t_out.size
    back = dyn.from_inertial(np.tile(basis, (k, 1)), np.repeat(t_out, 7)).reshape(k, 7, 6)
    b = np.transpose(back[:, 1:] - back[:, :1], (0, 2, 1))           # (K, 6, 6) d synodic / d gcrs
    extras = np.einsum("kij,kj->ki", b, e_in) if extra else e_in
    return dyn.from_inertial(s_in, t_out), np.einsum("kij,kjl,lm->kim", b, phi_in, a0), extras
