"""Compiled right-hand side of the ephemeris model: Earth, Moon and Sun from DE421 records.

Inertial geocentric GCRS axes, scaled like the CR3BP: position LU (384,400 km), velocity VU,
time TU (375,149 s) since the scenario epoch. With r the spacecraft, m the Moon and s the Sun
(geocentric), the acceleration is

    a = -GM_E r/|r|^3 + GM_M ((m - r)/|m - r|^3 - m/|m|^3) + GM_S ((s - r)/|s - r|^3 - s/|s|^3)
        + a_J2 + a_SRP

- a_J2 = -(3/2) J2 GM_E R_E^2 / |r|^5 ((1 - 5 (r.k)^2/|r|^2) r + 2 (r.k) k), k the Earth's pole;
- a_SRP = P A_U^2 / |r - s|^2 (r - s)/|r - s| (cannonball, no eclipses), P the radiation
  acceleration at 1 AU (C_R (A/m) 4.56e-6 N/m^2).

The Moon and Sun come from DE421's own records packed into the parameter vector (no refit): the
geocentric Moon series, and one "Sun minus Earth-Moon barycentre" series (both 16-day series of
DE421 on the same grid, subtracted record by record), so s = (sun - emb) + m/(1+EMRAT). Both
are re-expressed exactly (polynomial algebra, then dropping powers below 1e-8 km for the Moon and
1e-5 km for the Sun) on one grid of 6-hour records in the power basis, so one Horner loop of six
independent chains evaluates both (:func:`pack_params`).

Parameter vector layout (float64; written by :func:`pack_params`)::

    [GM_E, GM_M, GM_S, J2, R_E, kx, ky, kz, P_SRP, AU, EARTH_SHARE, MOON_BODY,
     series: start, 1/length, nrec, ncoef, offset, coefficients ...]

(GM in LU^3/TU^2, lengths in LU, times in TU; MOON_BODY is the index of the Moon among the
impact bodies, -1 when the Moon is not an impact body).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from cistrack.astro.ephemeris import ChebyshevSeries
from cistrack.lazy import lazy_njit
from cistrack.propagation.lane_rhs import LaneRecord

__all__ = ["ephemeris_rhs", "ephemeris_body_position", "pack_params", "bodies_position",
           "resample_power_basis", "HEADER_SIZE", "SERIES_HDR", "NCOEF", "NSUN", "MOON_SPEED_BOUND_KMS",
           "MOON_ACCELERATION_BOUND_KMS2"]

GM_E, GM_M, GM_S, J2, R_E, KX, KY, KZ, P_SRP, AU, EARTH_SHARE, MOON_BODY = range(12)
SERIES_HDR = 12
NCOEF = 8
"""Powers per record that the compiled functions evaluate (a constant, so that the Horner loop is
unrolled: the lockstep kernel then evaluates it with every lane's loads at one address).
DE421 on 6-hour records needs 8 everywhere from 1950 to 2046 (measured every 4 years);
:func:`pack_params` pads fewer with leading zeros (exact) and refuses more."""
NSUN = 5
"""Powers of the Sun-minus-barycentre series that the compiled functions evaluate (its records hold
:data:`NCOEF` rows, the higher ones zero): DE421's Sun on 6-hour records, with powers below 1e-5 km
dropped, needs 5 from 1950 to 2045 (measured at 1950, 1980, 2000, 2026 and 2045). Horner's rule
started at the highest nonzero power gives the same numbers as started at the zero rows
(``0 * u + a == a``), with 9 fewer loads and 18 fewer operations per evaluation."""
HEADER_SIZE = 17
MOON_SPEED_BOUND_KMS = 1.5
"""Bound on the Moon's geocentric speed, km/s, for the lockstep kernel's impact pre-test
(:meth:`cistrack.propagation.CompiledDynamics._bodies_arrays`); DE421 from 1900 to 2050, every
1.75 days: 0.966 to 1.104 km/s."""
MOON_ACCELERATION_BOUND_KMS2 = 4e-6
"""Bound on the Moon's geocentric acceleration, km/s^2, for the same pre-test (how far the Moon
strays from the chord between two grid positions); DE421's own second derivative from 1899-07-30
to 2053-10-08, every 1.2 hours: 2.41e-6 to 3.15e-6 km/s^2 (the Earth's pull at perigee, 356,376
km, is 3.18e-6)."""


# The compiled functions below (and :mod:`.ephemeris_point_mass_rhs`) repeat the same Horner evaluation on purpose: they are
# compiled lazily (``import`` must not load numba) and compiled code cannot call a lazily compiled
# helper. Each record holds power-basis coefficients in the record's normalised time u in [-1, 1],
# interleaved as ``[a0 mx, my, mz, sx, sy, sz, a1 mx, ...]``; Horner's rule runs the six
# coordinates side by side (six independent chains of multiply-adds), the Sun's from its
# highest nonzero power (:data:`NSUN`).

@lazy_njit(cache=True)
def bodies_position(p, t):
    """Geocentric Moon (mx, my, mz) and Sun-minus-barycentre (sx, sy, sz) at ``t``, LU."""
    start = p[SERIES_HDR]
    inv_length = p[SERIES_HDR + 1]
    nrec = int(p[SERIES_HDR + 2])
    off = int(p[SERIES_HDR + 4])
    v = (t - start) * inv_length
    k = int(np.floor(v))
    if k < 0:
        k = 0
    elif k > nrec - 1:
        k = nrec - 1
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
    return mx, my, mz, sx, sy, sz


@lazy_njit(cache=True)
def ephemeris_rhs(t, y, p, out):
    """Ephemeris equations of motion: y (6,) [LU, VU] geocentric GCRS -> out (6,) [VU, VU/TU]."""
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
    if p[GM_S] != 0.0 or p[P_SRP] != 0.0:
        f = p[EARTH_SHARE]
        sx += f * mx
        sy += f * my
        sz += f * mz
        ux = sx - x
        uy = sy - yy
        uz = sz - z
        u2 = ux * ux + uy * uy + uz * uz
        u1 = np.sqrt(u2)
        if p[GM_S] != 0.0:
            cu = p[GM_S] / (u2 * u1)
            s2 = sx * sx + sy * sy + sz * sz
            cs = p[GM_S] / (s2 * np.sqrt(s2))
            ax += cu * ux - cs * sx
            ay += cu * uy - cs * sy
            az += cu * uz - cs * sz
        if p[P_SRP] != 0.0:
            c = -p[P_SRP] * p[AU] * p[AU] / (u2 * u1)
            ax += c * ux
            ay += c * uy
            az += c * uz
    if p[J2] != 0.0:
        kx = p[KX]
        ky = p[KY]
        kz = p[KZ]
        rk = x * kx + yy * ky + z * kz
        re2 = p[R_E] * p[R_E]
        c = -1.5 * p[J2] * p[GM_E] * re2 / (r2 * r2 * r)
        q = 1.0 - 5.0 * rk * rk / r2
        ax += c * (q * x + 2.0 * rk * kx)
        ay += c * (q * yy + 2.0 * rk * ky)
        az += c * (q * z + 2.0 * rk * kz)
    out[0] = y[3]
    out[1] = y[4]
    out[2] = y[5]
    out[3] = ax
    out[4] = ay
    out[5] = az


@lazy_njit(cache=True)
def ephemeris_body_position(t, p, b, body_pos):
    """Position (x, y, z) LU of impact body ``b`` at ``t``: the Moon moves, the Earth is fixed."""
    if b == int(p[MOON_BODY]):
        start = p[SERIES_HDR]
        inv_length = p[SERIES_HDR + 1]
        nrec = int(p[SERIES_HDR + 2])
        off = int(p[SERIES_HDR + 4])
        v = (t - start) * inv_length
        k = int(np.floor(v))
        if k < 0:
            k = 0
        elif k > nrec - 1:
            k = nrec - 1
        u = 2.0 * (v - k) - 1.0
        j = off + (k * NCOEF + NCOEF - 1) * 6
        mx = p[j]
        my = p[j + 1]
        mz = p[j + 2]
        for _ in range(NCOEF - 1):  # the Moon's chains only (the Sun's are not needed here)
            j -= 6
            mx = mx * u + p[j]
            my = my * u + p[j + 1]
            mz = mz * u + p[j + 2]
        return mx, my, mz
    return body_pos[b, 0], body_pos[b, 1], body_pos[b, 2]


@lru_cache(maxsize=8)
def _chebyshev_to_power(ncheb: int) -> np.ndarray:
    """(ncheb, ncheb) read-only: row n holds T_n in powers of x (numpy's conversion, made once per
    size: a least-squares fit builds the ephemeris parameters thousands of times)."""
    to_power = np.zeros((ncheb, ncheb))
    for n in range(ncheb):
        row = np.polynomial.chebyshev.cheb2poly(np.eye(ncheb)[n])
        to_power[n, :row.size] = row
    to_power.flags.writeable = False
    return to_power


def resample_power_basis(series: ChebyshevSeries, start_s: float, length_s: float, nrec: int,
                         drop_below_km: float) -> np.ndarray:
    """Re-express a Chebyshev series on a finer grid of records, in the power basis.

    Record i covers [start_s + i length_s, start_s + (i+1) length_s], which must lie inside one
    record of ``series`` (the new grid subdivides the old one). Its polynomial in the local
    u in [-1, 1] is the series' own polynomial composed with the affine map u -> x (exact
    algebra; rounding only). Trailing powers whose largest magnitude over all records and axes is
    below ``drop_below_km`` are dropped. Returns (nrec, C, 3) coefficients, km.
    """
    cheb = np.asarray(series.coefficients, dtype=np.float64)
    parent = np.einsum("rac,cn->ran", cheb, _chebyshev_to_power(cheb.shape[2]))
    mid = start_s + (np.arange(nrec) + 0.5) * length_s
    k = np.floor((mid - series.start_s) / series.length_s).astype(np.int64)
    if np.any(k < 0) or np.any(k >= cheb.shape[0]):
        raise ValueError("resample_power_basis: the new records reach outside the series")
    alpha = length_s / series.length_s
    rec0 = start_s + np.arange(nrec) * length_s
    beta = 2.0 * (rec0 - series.start_s - k * series.length_s) / series.length_s - 1.0 + alpha
    a = parent[k]  # (nrec, 3, C)
    ncoef = a.shape[2]
    q = np.zeros_like(a)
    q[:, :, 0] = a[:, :, ncoef - 1]
    for n in range(ncoef - 2, -1, -1):  # Horner on polynomials: q <- q * (beta + alpha u) + a_n
        shifted = np.zeros_like(q)
        shifted[:, :, 1:] = q[:, :, :-1] * alpha
        q = q * beta[:, None, None] + shifted
        q[:, :, 0] += a[:, :, n]
    peak = np.max(np.abs(q), axis=(0, 1))
    keep = ncoef
    while keep > 2 and peak[keep - 1] < drop_below_km:
        keep -= 1
    return np.ascontiguousarray(np.transpose(q[:, :, :keep], (0, 2, 1)))


def pack_params(constants: np.ndarray, moon: ChebyshevSeries, sun_minus_emb: ChebyshevSeries,
                lu_km: float, tu_s: float, record_s: float = 21_600.0,
                moon_drop_below_km: float = 1e-8, sun_drop_below_km: float = 1e-5) -> np.ndarray:
    """The flat parameter vector: ``constants`` (12,) already scaled, then one joint series.

    DE421's Moon (4-day records) and Sun-minus-barycentre (16-day) series are re-expressed
    exactly on a common grid of ``record_s`` records (default 6 hours, which divides both), in the
    power basis, scaled to LU and TU; trailing powers below ``moon_drop_below_km`` (1e-8 km) and
    ``sun_drop_below_km`` (1e-5 km: the solar tide on a cislunar orbit changes by < 1e-17 km/s^2)
    are dropped; then padded to :data:`NCOEF` powers (more raise ``ValueError``, as do more than
    :data:`NSUN` for the Sun). Measured: 8 powers per record for the Moon and 5 for the Sun (11
    and 6 with 1-day records, which are therefore refused).
    """
    lo = max(moon.start_s, sun_minus_emb.start_s)
    hi = min(moon.end_s, sun_minus_emb.end_s)
    # start on the shared grid: DE421's records all start at JD 2414992.5 + multiples of 4 days
    lo = moon.start_s + np.ceil((lo - moon.start_s) / record_s - 1e-9) * record_s
    nrec = int(np.floor((hi - lo) / record_s + 1e-9))
    if nrec < 1:
        raise ValueError("pack_params: the Moon and Sun series do not overlap")
    m = resample_power_basis(moon, lo, record_s, nrec, moon_drop_below_km)
    s = resample_power_basis(sun_minus_emb, lo, record_s, nrec, sun_drop_below_km)
    ncoef = max(m.shape[1], s.shape[1])
    if ncoef > NCOEF:
        raise ValueError(f"pack_params: {record_s:g} s records need {ncoef} powers, the kernel evaluates "
                         f"NCOEF = {NCOEF}; use shorter records (the default 21600 s needs 8)")
    if s.shape[1] > NSUN:
        raise ValueError(f"pack_params: the Sun's series on {record_s:g} s records needs {s.shape[1]} powers "
                         f"(above {sun_drop_below_km:g} km), the kernel evaluates NSUN = {NSUN}; use shorter "
                         "records or a larger sun_drop_below_km (the defaults need 5)")
    ncoef = NCOEF  # zero leading powers change no value: 0 * u + a == a
    joint = np.zeros((nrec, ncoef, 6))
    joint[:, :m.shape[1], :3] = m
    joint[:, :s.shape[1], 3:] = s
    joint /= lu_km
    const = np.asarray(constants, dtype=np.float64).reshape(HEADER_SIZE - 5)
    header = np.array([lo / tu_s, tu_s / record_s, nrec, ncoef, HEADER_SIZE], dtype=np.float64)
    return np.concatenate([const, header, joint.reshape(-1)])
