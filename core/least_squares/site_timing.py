"""One site's clock offset, tested against a least-squares fit of several sites.

A site whose recorded times are late by ``dt`` (recorded = true + dt) sees the object where the
orbit puts it ``dt`` earlier: its residuals are ``r_i = -zdot_i dt`` (``zdot_i`` the rate of the
predicted measurement, the site's own motion included). Linearised at the fit, with the whitened
residuals ``r``, the whitened Jacobian ``A`` of the state and the whitened column ``c`` of the
offset (``-zdot_i / sigma_i`` on the site's rows, 0 elsewhere), the part of ``c`` that the state
cannot absorb is ``c~ = (I - A A^+) c``, and

    dt = c~.r / c~.c~,    sigma(dt) = 1 / |c~|,    drop = (c~.r)^2 / c~.c~

(the chi-square the offset removes, 1 degree of freedom). With a single site a common offset is
an orbit shifted along its track (``c~`` vanishes); with two sites the test tells only their
relative offset. A clock 30 s late at one of two survey sites had been absorbed into a
"converged; well determined" fit whose truth sat at Mahalanobis^2 3,588, or reported as a burn of
1.24 m/s on an object that never maneuvered.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from cistrack import units
from cistrack.least_squares.chi_square import chi2_ppf
from cistrack.least_squares.differential_correction import whitened_jacobian
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.result import FitResult
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.model.measurement import MeasurementSet

__all__ = ["SiteTiming", "site_timings", "timing_limit", "with_site_times_shifted", "TIMING_FALSE_ALARM"]

TIMING_FALSE_ALARM = 1e-4
"""Chance that a site with a right clock is called off (one site, one degree of freedom)."""
RATE_STEP_S = 30.0
"""Half the time step (s) of the central difference that gives each predicted measurement's rate."""


@dataclass(frozen=True)
class SiteTiming:
    """The clock offset of one site that the fit's residuals support.

    site : str          the site key
    n : int             its observations in the fit (rejected ones left out)
    offset_s : float    recorded minus true time, s (positive: the site's times are late)
    sigma_s : float     its one sigma, s
    drop : float        the chi-square the offset removes (1 degree of freedom)
    absorbed_per_s : (6 + P,) float   the linearised ``A^+ c`` per second of offset: the fit's state
                        (at its epoch; LU, VU) and its ``also`` parameters (their units) with the
                        offset fitted too are these minus ``absorbed_per_s * offset_s``, and their
                        covariance grows by ``absorbed_per_s absorbed_per_s^T sigma_s^2``
    """

    site: str
    n: int
    offset_s: float
    sigma_s: float
    drop: float
    absorbed_per_s: np.ndarray = field(default_factory=lambda: np.zeros(6), compare=False, repr=False)


def timing_limit() -> float:
    """The drop (chi-square, 1 degree of freedom) beyond which a site's offset is not noise."""
    return float(chi2_ppf(1.0 - TIMING_FALSE_ALARM, 1))


def site_timings(dynamics: Any, sensor: Any, ms: MeasurementSet, result: FitResult,
                 also: tuple[str, ...] = ()) -> list[SiteTiming]:
    """One :class:`SiteTiming` per site with observations in the fit ``result`` of ``ms`` (times
    TU, angles rad) tied to another site's in time (:func:`_tied`), largest drop first; [] with
    fewer than two sites. Linearised at the fit (the module docstring); the solve-for parameters
    held at their estimates, except ``also`` (names among ``result.parameter_names``: a fit with
    burns, their delta-v), whose columns the offset is projected against with the state's (what
    the burns absorb of a site's clock is not left to it)."""
    used = ~np.asarray(result.residuals.rejected, dtype=bool)
    if ms.sites is None or len(set(np.asarray(ms.sites)[used].tolist())) < 2:
        return []
    dyn = _fitted(dynamics, result)
    model = MeasurementModel(sensor, ms)
    states, a = _columns(dyn, model, result, tuple(also))
    a = a[used].reshape(-1, a.shape[-1])
    r = (model.residuals(states) / model.sigmas)[used].reshape(-1)
    rate = _rates(dyn, sensor, ms, result) / model.sigmas
    q, upper = np.linalg.qr(a)
    r = r - q @ (q.T @ r)
    sites = np.asarray(ms.sites).astype(str)
    out = []
    for site in _tied(np.asarray(model.times, dtype=float)[used], sites[used]):
        c = np.where((sites == site)[:, None], -rate, 0.0)[used].reshape(-1)
        absorbed = q.T @ c
        c = c - q @ absorbed
        cc = float(c @ c)
        if not cc > 0.0:
            continue
        cr = float(c @ r)
        per_s = np.linalg.solve(upper, absorbed) * units.days_to_tu(1.0 / 86400.0)
        out.append(SiteTiming(site, int(np.sum(used & (sites == site))), _seconds(cr / cc), _seconds(1.0 / np.sqrt(cc)),
                              cr * cr / cc, per_s))
    return sorted(out, key=lambda s: -s.drop)


def _columns(dynamics: Any, model: MeasurementModel, result: FitResult, also: tuple[str, ...]):
    """(states (K, 6), whitened Jacobian (K, m, 6 + len(also))) of the fit ``result`` along the
    fitted ``dynamics``: the state's columns, and ``also``'s parameters' (the fit's own Jacobian,
    :func:`~cistrack.least_squares.differential_correction.whitened_jacobian`)."""
    states, stms = arc_states_and_stms(dynamics, result.state, result.epoch, model.times)
    if not also:
        return states, np.einsum("kmi,kij->kmj", model.jacobian(states), stms) / model.sigmas[..., None]
    names = list(result.parameter_names)
    values = [float(result.parameters[names.index(n)]) for n in also]
    return states, whitened_jacobian(dynamics, model, result.state, result.epoch, also, values)


def with_site_times_shifted(ms: MeasurementSet, site: str, seconds: float) -> MeasurementSet:
    """``ms`` with the times of ``site``'s rows ``seconds`` later (a negative value corrects a late
    clock), rows put back in time order."""
    t = np.asarray(ms.times, dtype=float).copy()
    rows = np.asarray(ms.sites).astype(str) == site
    t[rows] += units.days_to_tu(seconds / 86400.0)
    order = np.argsort(t, kind="stable")
    return MeasurementSet(t[order], ms.values[order], ms.sigmas[order], ms.names, dict(ms.meta),
                          np.asarray(ms.sites)[order], None if ms.kinds is None else ms.kinds[order],
                          dict(ms.site_table))


TIED_DAYS = 5.0
"""How near (days) another site's observation must come to one of a site's for the site's clock to
be tested (:func:`_tied`): 2.5 days at most on the survey sets whose clocks were measured, 22.5
days for P13 in the development set of 2025-010D."""


def _tied(times: np.ndarray, sites: np.ndarray) -> list[str]:
    """The sites, in order of first appearance, with another site's observation within
    :data:`TIED_DAYS` of one of theirs (times (K,) TU, sites (K,) str). A site whose observations
    lie weeks from every other's is not tested: its clock is an along-track shift of its stretch of
    the arc, which the dynamics model's errors over the gap mimic (P13 in the development set of
    2025-010D, its 6 days 23 days before the others: "11 s late" at a chi-square of 17)."""
    reach = units.days_to_tu(TIED_DAYS)
    out = []
    for site in dict.fromkeys(sites.tolist()):
        own, others = times[sites == site], times[sites != site]
        if others.size and np.min(np.abs(others[:, None] - own[None, :])) <= reach:
            out.append(site)
    return out


def _fitted(dynamics: Any, result: FitResult) -> Any:
    names = tuple(getattr(result, "parameter_names", ()) or ())
    if not names:
        return dynamics
    return dynamics.with_parameters(**{n: float(v) for n, v in zip(names, result.parameters)})


def _rates(dynamics: Any, sensor: Any, ms: MeasurementSet, result: FitResult) -> np.ndarray:
    """d z / d t (K, m) per TU of each row's predicted measurement along the fitted orbit, the
    site's motion included: a central difference of :data:`RATE_STEP_S`."""
    h = units.days_to_tu(RATE_STEP_S / 86400.0)
    z = []
    for step in (h, -h):
        moved = replace(ms, times=np.asarray(ms.times, dtype=float) + step)
        model = MeasurementModel(sensor, moved)
        states, _ = arc_states_and_stms(dynamics, result.state, result.epoch, model.times)
        z.append(model.predict(states))
    d = z[0] - z[1]
    angular = MeasurementModel(sensor, ms).angular
    d[:, angular] = (d[:, angular] + np.pi) % (2.0 * np.pi) - np.pi
    return d / (2.0 * h)


def _seconds(tu: float) -> float:
    return float(units.tu_to_days(tu)) * 86400.0
