"""Compiled loops of the synodic <-> GCRS state conversions of :class:`.earth_moon.EarthMoonFrame`.

The ephemeris model converts every particle at both ends of each propagation call and at every
output time. These loops do, in one pass over the states, the operations of the numpy
formulation (scale, rotate with ``einsum``, cross product, shift, scale back), each product and
sum in its order. The rotation's three-term sums are in the order numpy's ``einsum`` takes on
AVX-512 (numpy 2.4): (0 + 2) + 1 for ``"nij,nj->ni"``, whose terms are contiguous (its vector
loop pairs them), (0 + 1) + 2 for ``"nji,nj->ni"``; so the numbers do not depend on which vector
loops a machine's numpy picks.

``rot`` (M, 3, 3), ``origin``, ``origin_v`` and ``omega`` (M, 3) hold the frame at one time
(M = 1, shared by every state) or at each state's time (M = N): :class:`.earth_moon.FrameAxes`.
"""
from __future__ import annotations

from cistrack.lazy import lazy_njit

__all__ = ["synodic_to_gcrs_into", "gcrs_to_synodic_into"]


@lazy_njit(cache=True)
def synodic_to_gcrs_into(s, rot, origin, origin_v, omega, lu_km, vu_kms, div_r, div_v, out):
    """Synodic states ``s`` (N, 6) [LU, VU] -> ``out`` (N, 6): GCRS in km and km/s divided by
    ``div_r`` and ``div_v`` (1.0 for km; LU_KM and VU_KMS for the kernels' LU and VU)."""
    many = rot.shape[0] > 1
    for n in range(s.shape[0]):
        k = n if many else 0
        px = s[n, 0] * lu_km
        py = s[n, 1] * lu_km
        pz = s[n, 2] * lu_km
        vx = s[n, 3] * vu_kms
        vy = s[n, 4] * vu_kms
        vz = s[n, 5] * vu_kms
        r0 = rot[k, 0, 0] * px + rot[k, 0, 2] * pz + rot[k, 0, 1] * py
        r1 = rot[k, 1, 0] * px + rot[k, 1, 2] * pz + rot[k, 1, 1] * py
        r2 = rot[k, 2, 0] * px + rot[k, 2, 2] * pz + rot[k, 2, 1] * py
        d0 = rot[k, 0, 0] * vx + rot[k, 0, 2] * vz + rot[k, 0, 1] * vy
        d1 = rot[k, 1, 0] * vx + rot[k, 1, 2] * vz + rot[k, 1, 1] * vy
        d2 = rot[k, 2, 0] * vx + rot[k, 2, 2] * vz + rot[k, 2, 1] * vy
        c0 = omega[k, 1] * r2 - omega[k, 2] * r1
        c1 = omega[k, 2] * r0 - omega[k, 0] * r2
        c2 = omega[k, 0] * r1 - omega[k, 1] * r0
        out[n, 0] = (origin[k, 0] + r0) / div_r
        out[n, 1] = (origin[k, 1] + r1) / div_r
        out[n, 2] = (origin[k, 2] + r2) / div_r
        out[n, 3] = (origin_v[k, 0] + d0 + c0) / div_v
        out[n, 4] = (origin_v[k, 1] + d1 + c1) / div_v
        out[n, 5] = (origin_v[k, 2] + d2 + c2) / div_v


@lazy_njit(cache=True)
def gcrs_to_synodic_into(s, mul_r, mul_v, rot, origin, origin_v, omega, lu_km, vu_kms, out):
    """GCRS states ``s`` (N, 6) times ``mul_r`` and ``mul_v`` in km and km/s (1.0 for km; LU_KM
    and VU_KMS for the kernels' LU and VU) -> ``out`` (N, 6) synodic [LU, VU]."""
    many = rot.shape[0] > 1
    for n in range(s.shape[0]):
        k = n if many else 0
        e0 = s[n, 0] * mul_r - origin[k, 0]
        e1 = s[n, 1] * mul_r - origin[k, 1]
        e2 = s[n, 2] * mul_r - origin[k, 2]
        c0 = omega[k, 1] * e2 - omega[k, 2] * e1
        c1 = omega[k, 2] * e0 - omega[k, 0] * e2
        c2 = omega[k, 0] * e1 - omega[k, 1] * e0
        f0 = s[n, 3] * mul_v - origin_v[k, 0] - c0
        f1 = s[n, 4] * mul_v - origin_v[k, 1] - c1
        f2 = s[n, 5] * mul_v - origin_v[k, 2] - c2
        out[n, 0] = (rot[k, 0, 0] * e0 + rot[k, 1, 0] * e1 + rot[k, 2, 0] * e2) / lu_km
        out[n, 1] = (rot[k, 0, 1] * e0 + rot[k, 1, 1] * e1 + rot[k, 2, 1] * e2) / lu_km
        out[n, 2] = (rot[k, 0, 2] * e0 + rot[k, 1, 2] * e1 + rot[k, 2, 2] * e2) / lu_km
        out[n, 3] = (rot[k, 0, 0] * f0 + rot[k, 1, 0] * f1 + rot[k, 2, 0] * f2) / vu_kms
        out[n, 4] = (rot[k, 0, 1] * f0 + rot[k, 1, 1] * f1 + rot[k, 2, 1] * f2) / vu_kms
        out[n, 5] = (rot[k, 0, 2] * f0 + rot[k, 1, 2] * f1 + rot[k, 2, 2] * f2) / vu_kms
