"""Gauss's angles-only IOD (two-body), as a baseline that shows why Keplerian IOD fails in
cislunar space.

The core, :func:`gauss_angles_only`, is the classical method (Curtis, *Orbital Mechanics for
Engineering Students*, Algorithm 5.5; Vallado, *Fundamentals of Astrodynamics*, sec. 7.3):
three lines of sight and observer positions in an inertial frame centred on the attracting
body, the f and g series truncated after the mu/r^3 terms, the eighth-degree polynomial in the
central radius, and v2 from the f and g of the outer observations. It is vectorised over
samples: the polynomial roots come from the eigenvalues of a stack of companion matrices.

The plugin ``"gauss"`` works in an Earth-centred inertial frame built from the synodic frame
(which turns at 1 rad/TU about z with the Earth at (-mu, 0, 0)); the Earth's gravitational
parameter is 1 - mu in LU^3/TU^2. It perturbs the angles of three fitted measurements (first,
middle, last of the kinematic fit window) per sample, solves, carries the middle state to the
last of the three times with the same truncated f and g series (so the cloud's epoch is the last
measurement used, as the IOD interface asks) and converts back to synodic:
v_syn = R^T v_eci - omega x (r_syn - r_earth).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces.component import check_int, check_positive, check_range, MemoryNeed, IOD_CHUNK_BYTES
from cistrack.errors import IODError
from cistrack.api import hookimpl
from cistrack.interfaces import IODMethod, Sensor
from cistrack.interfaces.iod import check_iod_particles
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.astro.rotating_frame import eci_to_synodic, rot_z, synodic_to_eci

from .kinematic_fit import prepare_fit

__all__ = ["GaussSolution", "gauss_angles_only", "synodic_to_eci", "eci_to_synodic", "GaussIOD",
           "MU_EARTH_MOON"]

@dataclass
class GaussSolution:
    """Result of :func:`gauss_angles_only` for N samples.

    r : (N, 3, 3) positions at t1, t2, t3 (same length unit as the inputs)
    v2 : (N, 3) velocity at t2
    v3 : (N, 3) velocity at t3 from the truncated f and g series
    slant_ranges : (N, 3)
    valid : (N,) bool, False where no positive real root gave positive slant ranges
    """

    r: np.ndarray
    v2: np.ndarray
    v3: np.ndarray
    slant_ranges: np.ndarray
    valid: np.ndarray


def _real_positive_root(a: np.ndarray, b: np.ndarray, c: np.ndarray, rho2_of) -> np.ndarray:
    """Largest positive real root x of x^8 + a x^6 + b x^3 + c = 0 with rho2_of(x) > 0; NaN if none.

    a, b, c : (N,). Roots from the eigenvalues of the companion matrices (N, 8, 8).
    """
    n = a.shape[0]
    comp = np.zeros((n, 8, 8))
    comp[:, 1:, :-1] = np.eye(7)
    # monic p(x) = x^8 + c7 x^7 + ... + c0: last column holds -c0 .. -c7
    coeffs = np.zeros((n, 8))
    coeffs[:, 6] = a
    coeffs[:, 3] = b
    coeffs[:, 0] = c
    comp[:, :, -1] = -coeffs
    roots = np.linalg.eigvals(comp)
    mag = np.abs(roots)
    real = np.abs(roots.imag) <= 1e-8 * np.maximum(mag, 1e-300)
    x = np.where(real & (roots.real > 0), roots.real, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = rho2_of(x) > 0
    x = np.where(ok, x, np.nan)
    with np.errstate(invalid="ignore"):
        best = np.nanmax(np.where(np.isnan(x), -np.inf, x), axis=1)
    return np.where(np.isfinite(best), best, np.nan)


@dataclass(frozen=True)
class _Intervals:
    """Time intervals of Gauss's method: tau1 = t1 - t2, tau3 = t3 - t2, tau = t3 - t1."""

    tau1: float
    tau3: float
    tau: float


def _intervals(times) -> _Intervals:
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.shape != (3,) or not (t[0] < t[1] < t[2]):
        raise IODError(f"Gauss's method needs three strictly increasing times, got {t}")
    tau1, tau3 = t[0] - t[1], t[2] - t[1]
    return _Intervals(tau1, tau3, tau3 - tau1)


def _observer_and_los(observer, los) -> tuple[np.ndarray, np.ndarray]:
    """Observer positions and lines of sight as broadcast (N, 3, 3) stacks."""
    R = np.asarray(observer, dtype=float)
    L = np.asarray(los, dtype=float)
    if R.ndim == 2:
        R = R[None]
    if L.ndim == 2:
        L = L[None]
    R, L = np.broadcast_arrays(R, L)
    return R, L


def _scalar_triples(R: np.ndarray, L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """D0 = l1 . (l2 x l3) (N,) and D[i, j] = R_i . p_j (N, 3, 3), p = (l2 x l3, l1 x l3, l1 x l2)."""
    l1, l2, l3 = L[:, 0], L[:, 1], L[:, 2]
    p1 = np.cross(l2, l3)
    p2 = np.cross(l1, l3)
    p3 = np.cross(l1, l2)
    d0 = np.einsum("ni,ni->n", l1, p1)
    p = np.stack([p1, p2, p3], axis=1)                       # (N, 3, 3): p_j rows
    return d0, np.einsum("nik,njk->nij", R, p)               # D[i, j] = R_i . p_j


def _central_radius(A, B, E, R2sq, mu: float) -> np.ndarray:
    """r2 (N,): the largest positive real root of x^8 + a x^6 + b x^3 + c = 0 with a positive
    middle slant range A + mu B / x^3; NaN where none."""
    a = -(A ** 2 + 2.0 * A * E + R2sq)
    b = -2.0 * mu * B * (A + E)
    c = -(mu * B) ** 2
    finite = np.isfinite(a) & np.isfinite(b) & np.isfinite(c)
    x = np.full(a.shape, np.nan)
    if finite.any():
        x[finite] = _real_positive_root(
            a[finite], b[finite], c[finite],
            lambda r: A[finite][:, None] + mu * B[finite][:, None] / r ** 3)
    return x


def _outer_ranges(D: np.ndarray, d0: np.ndarray, x3: np.ndarray, mu: float, iv: _Intervals):
    """Slant ranges rho1, rho3 (N,) given r2^3 = ``x3``."""
    tau1, tau3, tau = iv.tau1, iv.tau3, iv.tau
    rho1 = ((6.0 * (D[:, 2, 0] * tau1 / tau3 + D[:, 1, 0] * tau / tau3) * x3
             + mu * D[:, 2, 0] * (tau ** 2 - tau1 ** 2) * tau1 / tau3)
            / (6.0 * x3 + mu * (tau ** 2 - tau3 ** 2)) - D[:, 0, 0]) / d0
    rho3 = ((6.0 * (D[:, 0, 2] * tau3 / tau1 - D[:, 1, 2] * tau / tau1) * x3
             + mu * D[:, 0, 2] * (tau ** 2 - tau3 ** 2) * tau3 / tau1)
            / (6.0 * x3 + mu * (tau ** 2 - tau1 ** 2)) - D[:, 2, 2]) / d0
    return rho1, rho3


def _velocities(r: np.ndarray, x3: np.ndarray, mu: float, iv: _Intervals) -> tuple[np.ndarray, np.ndarray]:
    """v2 (N, 3) from the truncated f and g of the outer positions, and v3 (N, 3) carried from
    t2 by the derivatives of the same series."""
    tau1, tau3 = iv.tau1, iv.tau3
    f1 = 1.0 - 0.5 * mu * tau1 ** 2 / x3
    f3 = 1.0 - 0.5 * mu * tau3 ** 2 / x3
    g1 = tau1 - mu * tau1 ** 3 / (6.0 * x3)
    g3 = tau3 - mu * tau3 ** 3 / (6.0 * x3)
    v2 = (-f3[:, None] * r[:, 0] + f1[:, None] * r[:, 2]) / (f1 * g3 - f3 * g1)[:, None]
    fd3 = -mu * tau3 / x3
    gd3 = 1.0 - 0.5 * mu * tau3 ** 2 / x3
    return v2, fd3[:, None] * r[:, 1] + gd3[:, None] * v2


def gauss_angles_only(observer: np.ndarray, los: np.ndarray, times: np.ndarray,
                      mu: float) -> GaussSolution:
    """Gauss's method without iterative improvement, vectorised over samples.

    Parameters
    ----------
    observer : (N, 3, 3) or (3, 3)
        Observer positions R_i (row i for time i) in an inertial frame centred on the attracting
        body (e.g. km, or LU).
    los : (N, 3, 3) or (3, 3)
        Unit lines of sight rho_hat_i in the same frame.
    times : (3,)
        Observation times t1 < t2 < t3 (e.g. s, or TU).
    mu : float
        Gravitational parameter in the matching units (km^3/s^2, or LU^3/TU^2).

    Returns
    -------
    GaussSolution (r, v2, v3 in the input units; invalid samples are NaN).
    """
    R, L = _observer_and_los(observer, los)
    iv = _intervals(times)
    tau1, tau3, tau = iv.tau1, iv.tau3, iv.tau
    d0, D = _scalar_triples(R, L)
    E = np.einsum("ni,ni->n", R[:, 1], L[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        A = (-D[:, 0, 1] * tau3 / tau + D[:, 1, 1] + D[:, 2, 1] * tau1 / tau) / d0
        B = (D[:, 0, 1] * (tau3 ** 2 - tau ** 2) * tau3 / tau
             + D[:, 2, 1] * (tau ** 2 - tau1 ** 2) * tau1 / tau) / (6.0 * d0)
    x = _central_radius(A, B, E, np.einsum("ni,ni->n", R[:, 1], R[:, 1]), mu)
    x3 = x ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        rho1, rho3 = _outer_ranges(D, d0, x3, mu, iv)
        rho = np.stack([rho1, A + mu * B / x3, rho3], axis=1)
        r = R + rho[..., None] * L
        v2, v3 = _velocities(r, x3, mu, iv)
    valid = (np.isfinite(x) & np.all(rho > 0, axis=1) & np.all(np.isfinite(v2), axis=1))
    nan = ~valid
    r[nan] = np.nan
    v2[nan] = np.nan
    v3[nan] = np.nan
    return GaussSolution(r, v2, v3, rho, valid)


class GaussIOD(IODMethod):
    """Gauss's angles-only two-body IOD, Monte Carlo over perturbed angles (a baseline).

    Parameters
    ----------
    n_particles : int
        Particles wanted.
    max_oversampling : float
        Give up after drawing this multiple of n_particles when samples have no valid root.
    pass_gap_hours : float
        A gap between measurements longer than this ends the first pass, hours (as for the
        kinematic fit).
    fit_fraction : float
        Fraction of the first pass's measurements in the window (the earliest ones); Gauss uses the
        first, middle and last measurement of that window.
    min_fit, max_fit : int
        Bounds on the number of measurements in the window.
    mu : float
        Mass ratio of the synodic frame (the Earth's GM is 1 - mu in LU^3/TU^2).
    """

    def __init__(self, *, n_particles: int = 2000, max_oversampling: float = 10.0,
                 pass_gap_hours: float = 3.0, fit_fraction: float = 0.5, min_fit: int = 3,
                 max_fit: int = 12, mu: float = MU_EARTH_MOON) -> None:
        self.n_particles = check_iod_particles(self, n_particles)
        self.max_oversampling = check_range(self, "max_oversampling", max_oversampling, 1.0, 1e6)
        self.pass_gap_hours = check_positive(self, "pass_gap_hours", pass_gap_hours)
        self.fit_fraction = check_range(self, "fit_fraction", fit_fraction, 0.0, 1.0, lo_open=True)
        self.min_fit = check_int(self, "min_fit", min_fit, minimum=3)
        self.max_fit = check_int(self, "max_fit", max_fit, minimum=self.min_fit)
        self.mu = check_range(self, "mu", mu, 0.0, 0.5, lo_open=True)

    def memory_need(self) -> MemoryNeed:
        """The particles it returns plus one chunk of oversampled fits (``n_particles``)."""
        return MemoryNeed.particles(self.n_particles, IOD_CHUNK_BYTES)

    def estimate(self, measurements: MeasurementSet, sensor: Sensor,
                 rng: np.random.Generator) -> ParticleCloud:
        """Cloud (n_particles, 6), synodic, at the last of the three measurements used."""
        who = "iod 'gauss'"
        fit = prepare_fit(measurements, sensor, order=2, pass_gap_hours=self.pass_gap_hours,
                          fit_fraction=self.fit_fraction, min_fit=self.min_fit, max_fit=self.max_fit,
                          need_range=False, who=who)
        k = fit.times.shape[0]
        pick = np.array([0, k // 2, k - 1])
        times = fit.times[pick]
        rot = rot_z(times)                                          # (3, 3, 3)
        earth = np.array([-self.mu, 0.0, 0.0])
        obs_eci = np.einsum("kij,kj->ki", rot, fit.observer[pick] - earth)   # (3, 3)
        limit = int(np.ceil(self.max_oversampling * self.n_particles))
        kept: list[np.ndarray] = []
        n_kept = drawn = 0
        while n_kept < self.n_particles and drawn < limit:
            n = min(self.n_particles - n_kept + max(16, (self.n_particles - n_kept) // 4), limit - drawn)
            ang = fit.angles[pick][None] + fit.angle_sigmas[pick][None] * rng.standard_normal((n, 3, 2))
            tk = np.broadcast_to(times, (n, 3)).reshape(-1)
            los_syn = np.asarray(sensor.line_of_sight(ang.reshape(-1, 2), tk)).reshape(n, 3, 3)
            los_eci = np.einsum("kij,nkj->nki", rot, los_syn)
            sol = gauss_angles_only(obs_eci, los_eci, times, 1.0 - self.mu)
            eci = np.concatenate([sol.r[:, 2], sol.v3], axis=1)[sol.valid]
            kept.append(eci_to_synodic(eci, times[2], self.mu))
            n_kept += int(sol.valid.sum())
            drawn += n
        if n_kept < self.n_particles:
            raise IODError(f"{who}: only {n_kept} of {drawn} angle samples gave a positive real "
                           f"root with positive slant ranges (wanted {self.n_particles})")
        states = np.concatenate(kept)[: self.n_particles]
        meta = {"method": "gauss", "fit_indices": fit.indices[pick].tolist(),
                "fit_times": times.tolist(), "draws": drawn, "survivors": n_kept,
                "survival_fraction": n_kept / drawn, "pruned": {"no_valid_root": drawn - n_kept},
                "screened_out": fit.screened_record(measurements)}
        return ParticleCloud(states, float(times[2]), meta=meta)


@hookimpl
def cistrack_register(registry) -> None:
    registry.add("iod", "gauss", GaussIOD)
