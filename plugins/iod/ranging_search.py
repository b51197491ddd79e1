"""Systematic ranging over one tracklet's admissible region, scored on other tracklets.

The method of OrbFit's admissible region and Find_Orb's statistical ranging, with the scenario's
own dynamics. From a tracklet's attributable (:mod:`.tracklets`) every range rho and range rate
rho_dot gives a full synodic state. :func:`admissible_states` lays a grid over that plane: rho
log-spaced from ``range_min_km`` to ``range_max_km``, and for each rho the range rates whose
geocentric two-body energy stays below ``max_c3`` / 2 (C3 in km^2/s^2; 0 = bound to the Earth; a
little above 0 admits a slow escape through the Earth-Moon system), spread evenly between the two
roots of that bound. :func:`score_states` propagates all of them at once to the times of the
observations of other tracklets and scores each by the robust sum

    S = sum_k log(1 + chi2_k / SCORE_SCALE),   chi2_k = |wrapped (z_k - h(x(t_k))) / sigma_k|^2

which ranks a grid point near the orbit first even when one of those observations is a gross
outlier (a plain chi-square would be ruled by it). :func:`refine` starts the least squares
(:func:`cistrack.least_squares.fit_orbit`, outlier rejection on) from the best few grid points
that lie apart in range and keeps the best that converges.
"""
from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass

import numpy as np

from cistrack.errors import MeasurementError, PropagationError
from cistrack.interfaces import Dynamics, Sensor
from cistrack.least_squares import FitError, FitOptions, FitResult, UnobservableWarning, fit_orbit
from cistrack.model.measurement import MeasurementSet
from cistrack.units import LU_KM, VU_KMS

from .tracklets import Attributable, states_from_ranges

__all__ = ["admissible_states", "admissible_extent", "score_states", "refine", "ScoredGrid", "SCORE_SCALE", "MU_EARTH",
           "EARTH", "CLEAN_NOISE_SCALE"]

CLEAN_NOISE_SCALE = 1.5
"""A fit whose noise scale (residuals over their stated noise, 1 for noise) is below this fits its
observations (the least squares' own bound on a clean fit, ``burn_search.MAX_RMS``); above it, a fit
that converged sits in a false minimum or holds bad data."""
SCORE_SCALE = 25.0
"""chi2 of one observation at which its score term is log 2 (5 sigma)."""
MU_EARTH = 1.0 - 1.2150582e-2
"""The Earth's share of the Earth-Moon gravitational parameter, LU^3/TU^2."""
EARTH = np.array([-1.2150582e-2, 0.0, 0.0])
"""The Earth in the synodic frame, LU."""


def _inertial_velocity_offset(r: np.ndarray) -> np.ndarray:
    """omega x (r - r_earth) (N, 3) VU: synodic velocity + this = geocentric inertial velocity."""
    d = r - EARTH
    return np.stack([-d[:, 1], d[:, 0], np.zeros(len(d))], axis=1)


def _rate_bounds(att: Attributable, rho: np.ndarray, max_c3: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(admissible (N,) bool, middle and half-width of the range rates (N,) VU) at the ranges ``rho`` (N,) LU:
    the roots of the energy bound (module docstring); a range is admissible when the bound leaves
    a rate there and the position lies 100 km above the Earth."""
    zero = states_from_ranges(att, rho, np.zeros_like(rho))
    w = zero[:, 3:] + _inertial_velocity_offset(zero[:, :3])     # inertial velocity at rho_dot = 0
    r = np.linalg.norm(zero[:, :3] - EARTH, axis=1)
    v2_max = max_c3 / VU_KMS ** 2 + 2.0 * MU_EARTH / r
    uw = w @ att.u
    disc = uw * uw - np.sum(w * w, axis=1) + v2_max
    ok = (disc > 0) & (r * LU_KM > 6378.137 + 100.0)
    return ok, -uw, np.sqrt(np.where(ok, disc, 0.0))


def admissible_states(att: Attributable, *, n_range: int, n_rate: int, range_min_km: float,
                      range_max_km: float, max_c3: float) -> tuple[np.ndarray, np.ndarray]:
    """(states (N, 6) LU, VU synodic at ``att.t``, ranges (N,) km): the grid over the admissible
    region (see the module docstring); N <= n_range * n_rate (ranges whose energy bound leaves
    no rate, and positions inside the Earth, are left out)."""
    rho = np.geomspace(range_min_km, range_max_km, n_range) / LU_KM
    ok, mid, half = _rate_bounds(att, rho, max_c3)
    frac = (np.arange(n_rate) + 0.5) / n_rate                       # midpoints of n_rate equal cells
    rates = (mid - half)[:, None] + (2.0 * half)[:, None] * frac[None]
    rr = np.repeat(rho[ok], n_rate)
    return states_from_ranges(att, rr, rates[ok].reshape(-1)), rr * LU_KM


def admissible_extent(att: Attributable, *, range_min_km: float, range_max_km: float, max_c3: float,
                      n_range: int = 20000) -> dict:
    """The admissible region of one tracklet in numbers: the admissible ranges (km; lowest and
    highest of ``n_range`` log-spaced from ``range_min_km`` to ``range_max_km``, a step of 0.035 %
    by default), the range rates (km/s) the energy bound allows over them, and the bound itself;
    empty when no range is admissible."""
    rho = np.geomspace(range_min_km, range_max_km, n_range) / LU_KM
    ok, mid, half = _rate_bounds(att, rho, max_c3)
    if not np.any(ok):
        return {}
    return {"range_km": [float(rho[ok].min() * LU_KM), float(rho[ok].max() * LU_KM)],
            "range_rate_kms": [float((mid - half)[ok].min() * VU_KMS), float((mid + half)[ok].max() * VU_KMS)],
            "max_c3_km2_s2": float(max_c3), "range_bounds_km": [float(range_min_km), float(range_max_km)]}


def _propagate(dynamics: Dynamics, states: np.ndarray, t0: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(states (K, N, 6) at ``times`` (K,) TU in any order, alive (N,)): forward and backward
    from ``t0`` separately (a propagation goes one way)."""
    out = np.empty((times.size, states.shape[0], 6))
    alive = np.ones(states.shape[0], dtype=bool)
    for side in (times >= t0, times < t0):
        if not side.any():
            continue
        ts = times[side]
        order = np.argsort(ts) if ts[0] >= t0 else np.argsort(-ts)
        prop = dynamics.propagate(states, t0, ts[order])
        part = np.empty_like(prop.states)
        part[order] = prop.states
        out[side] = part
        alive &= np.asarray(prop.alive, dtype=bool)
    return out, alive


def score_states(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, rows: np.ndarray,
                 states: np.ndarray, t0: float) -> np.ndarray:
    """Robust score (N,) of each state (N, 6) at ``t0`` TU against the observations ``rows`` (K,)
    of ``ms`` (lower is better; inf for a state that hits a body or cannot be measured)."""
    rows = np.asarray(rows, dtype=int)
    times = ms.times[rows]
    with np.errstate(all="ignore"):
        traj, alive = _propagate(dynamics, states, float(t0), times)
        score = np.zeros(states.shape[0])
        for j, i in enumerate(rows):
            m = ms[int(i)]
            s = sensor.for_measurement(m)
            zhat = np.asarray(s.measure(traj[j], float(m.t)), dtype=float)[:, :2]
            r = s.residual(np.broadcast_to(m.z[:2], zhat.shape), zhat) / ms.sigmas[i, :2]
            score += np.log1p(np.sum(r * r, axis=1) / SCORE_SCALE)
    score[~alive | ~np.isfinite(score)] = np.inf
    return score


@dataclass(frozen=True)
class ScoredGrid:
    """Grid states (N, 6) LU, VU synodic at ``t0`` TU, their ranges (N,) km and scores (N,)."""

    states: np.ndarray
    rho_km: np.ndarray
    score: np.ndarray
    t0: float


def _distinct(order: np.ndarray, rho_km: np.ndarray, how_many: int, spacing: float = 0.1) -> list[int]:
    """Up to ``how_many`` indices from ``order`` whose ranges differ by more than ``spacing``
    (relative) from every one taken before."""
    taken: list[int] = []
    for i in order:
        if all(abs(np.log(rho_km[i] / rho_km[j])) > spacing for j in taken):
            taken.append(int(i))
        if len(taken) >= how_many:
            break
    return taken


def _one_fit(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, state: np.ndarray, t0: float,
             options: FitOptions) -> FitResult | None:
    """fit_orbit with its warnings kept in its messages; None when it cannot be made."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnobservableWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            return fit_orbit(dynamics, sensor, ms, state, t0, options=options)
        except (FitError, PropagationError, MeasurementError, np.linalg.LinAlgError):
            return None


def _quality(fit: FitResult | None) -> float:
    """Lower is better: the weighted RMS of a converged fit, inf otherwise."""
    if fit is None or not fit.converged or not np.isfinite(fit.rms):
        return np.inf
    return float(fit.rms) * (1.0 + fit.n_rejected / max(fit.n_used, 1))


def refine(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, rows: np.ndarray, grid: ScoredGrid, *,
           tries: int, options: FitOptions, progress: RangingProgress | None = None) -> tuple[FitResult | None, int, int]:
    """(best fit or None, index of the grid state it started from, fits tried): the least squares
    on the observations ``rows`` from the ``tries`` best-scored grid states that lie apart in range;
    the best converged fit by weighted RMS (rejections count against it), its state at
    ``grid.t0``. Stops early at a fit whose noise scale is below :data:`CLEAN_NOISE_SCALE`.
    ``progress``: the IOD's (:class:`RangingProgress`; default one of its own)."""
    sub = ms.subset(np.asarray(rows, dtype=int))
    order = np.argsort(grid.score, kind="stable")
    order = order[np.isfinite(grid.score[order])]
    best, best_i, tried = None, -1, 0
    progress = progress or RangingProgress()
    progress.large(len(sub), tries)
    for i in _distinct(order, grid.rho_km, tries):
        tried += 1
        fit = _one_fit(dynamics, sensor, sub, grid.states[i], grid.t0, options)
        if _quality(fit) < _quality(best):
            best, best_i = fit, i
        if best is not None and best.converged and best.noise_scale < CLEAN_NOISE_SCALE:
            break
        progress.step(tried, tries)
    return best, best_i, tried


LARGE_FIT_ROWS = 5000
"""Observations in one range trial's least squares beyond which :func:`refine` says up front that
it is slow: a 35 MB file's tracklet of about 400,000 rows sat in it for minutes with no word."""


class RangingProgress:
    """Lines on the ``cistrack`` logger while the ranging IOD runs: what it is doing (which seed
    tracklet, how many range trials fitted) every :attr:`every_s` seconds from its start, across
    all its seeds (a 30-observation file had sat 22-37 s in it with no word, each seed's trials
    under 10 s: probe N16), and one up front when a trial fits :data:`LARGE_FIT_ROWS`
    observations or more."""

    every_s = 10.0

    def __init__(self) -> None:
        self.next, self.where = time.monotonic() + self.every_s, "the seed tracklets"

    def large(self, rows: int, tries: int) -> None:
        """The line up front when one trial fits ``rows`` observations (up to ``tries`` trials)."""
        if rows >= LARGE_FIT_ROWS:
            self._say(f"each range trial is a least squares over {rows:,} observations (up to {tries} trials); "
                      "a file this dense takes minutes")

    def seed(self, k: int, size: int, trial: int, trials: int) -> None:
        """Now ranging from tracklet ``k`` (0-based; ``size`` observations), seed trial ``trial``
        (1-based) of up to ``trials``."""
        self.where = f"from seed tracklet {k + 1} ({size} observations; seed trial {trial} of up to {trials})"
        self.step(0, 0)

    def step(self, tried: int, tries: int) -> None:
        """``tried`` of up to ``tries`` range trials of the current seed fitted: a line when due."""
        if time.monotonic() >= self.next:
            fitted = f", {tried} of up to {tries} range trials fitted" if 0 < tried < tries else ""
            self._say(f"ranging {self.where}{fitted} ...")
            self.next = time.monotonic() + self.every_s

    @staticmethod
    def _say(text: str) -> None:
        logging.getLogger("cistrack").info(f"iod 'tracklet-ranging': {text}")
