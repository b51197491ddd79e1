"""The ephemeris model's right-hand side without Earth J2 and radiation pressure.

:func:`ephemeris_point_mass_rhs` is :func:`.ephemeris_rhs.ephemeris_rhs` with those two terms'
code removed: the same numbers bit for bit when they are off (``p[J2] == p[P_SRP] == 0``), and
the function the model integrates then (:meth:`.ephemeris.EphemerisDynamics._rhs`). Written out
again rather than shared because compiled code cannot call a lazily compiled helper, and because
the point is what the compiled stages do not contain: a lane-invariant ``if`` inside the lockstep
kernel's vectorised lane loop is if-converted by LLVM, which computes both sides (J2's two
divisions in every stage of every lane, measured with ``benchmarks/bench_stage_cost.py``).
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import lazy_njit
from cistrack.propagation.lane_rhs import LaneRecord

from .ephemeris_rhs import EARTH_SHARE, GM_E, GM_M, GM_S, NCOEF, NSUN, SERIES_HDR

__all__ = ["ephemeris_point_mass_rhs"]


@lazy_njit(cache=True)
def ephemeris_point_mass_rhs(t, y, p, out):
    """Point-mass Earth, Moon and Sun: y (6,) [LU, VU] geocentric GCRS -> out (6,) [VU, VU/TU].

    The Sun's terms are unconditional: with ``p[GM_S] == 0`` (``sun = false``) they add exactly zero."""
    start = p[SERIES_HDR]
    inv_length = p[SERIES_HDR + 1]
    nrec = int(p[SERIES_HDR + 2])
    off = int(p[SERIES_HDR + 4])
    v = (t - start) * inv_length
    # the record: lanes of the lockstep kernel in the same record share its coefficient loads
    k: LaneRecord = min(max(int(np.floor(v)), 0), nrec - 1)
    u = 2.0 * (v - k) - 1.0
    j = off + (k * NCOEF + NCOEF - 1) * 6
    mx = p[j]
    my = p[j + 1]
    mz = p[j + 2]
    for _ in range(NCOEF - NSUN):
        j -= 6
        mx = mx * u + p[j]
        my = my * u + p[j + 1]
        mz = mz * u + p[j + 2]
    sx = p[j + 3]
    sy = p[j + 4]
    sz = p[j + 5]
    for _ in range(NSUN - 1):
        j -= 6
        mx = mx * u + p[j]
        my = my * u + p[j + 1]
        mz = mz * u + p[j + 2]
        sx = sx * u + p[j + 3]
        sy = sy * u + p[j + 4]
        sz = sz * u + p[j + 5]
    x = y[0]
    yy = y[1]
    z = y[2]
    r2 = x * x + yy * yy + z * z
    r = np.sqrt(r2)
    ce = -p[GM_E] / (r2 * r)
    ax = ce * x
    ay = ce * yy
    az = ce * z
    # Moon: direct and indirect terms
    dx = mx - x
    dy = my - yy
    dz = mz - z
    d2 = dx * dx + dy * dy + dz * dz
    cd = p[GM_M] / (d2 * np.sqrt(d2))
    m2 = mx * mx + my * my + mz * mz
    cm = p[GM_M] / (m2 * np.sqrt(m2))
    ax += cd * dx - cm * mx
    ay += cd * dy - cm * my
    az += cd * dz - cm * mz
    # Sun: direct and indirect terms
    f = p[EARTH_SHARE]
    sx += f * mx
    sy += f * my
    sz += f * mz
    ux = sx - x
    uy = sy - yy
    uz = sz - z
    u2 = ux * ux + uy * uy + uz * uz
    u1 = np.sqrt(u2)
    cu = p[GM_S] / (u2 * u1)
    s2 = sx * sx + sy * sy + sz * sz
    cs = p[GM_S] / (s2 * np.sqrt(s2))
    ax += cu * ux - cs * sx
    ay += cu * uy - cs * sy
    az += cu * uz - cs * sz
    out[0] = y[3]
    out[1] = y[4]
    out[2] = y[5]
    out[3] = ax
    out[4] = ay
    out[5] = az
