"""The residual ladder: how far a fit's prediction misses each earlier arc.

The fit (state and covariance at its epoch; the covariance times the noise scale squared when
that exceeds 1, as the export does) is carried back to every observation of an earlier arc by
:func:`cistrack.least_squares.prediction.predict_orbit` (the covariance by the unscented
transform). Per observation i, with r_i the O - C (rad) against the predicted state, H_i the
measurement Jacobian (m, 6) there, P_i the predicted covariance and R_i the noise:

    S_i = H_i P_i H_i^T + R_i,    d_i^2 = r_i^T S_i^-1 r_i    (chi-square, m degrees of freedom)

A rung's **miss in sigmas** is the median of d_i over the arc. The arc is **consistent** with the
fit when the median d_i^2 is at most the chi-square quantile of probability 1 - 5e-4
(:data:`LINK_TAIL` / 2; 15.2 for two angles): whatever the correlation between the d_i (they
share the fit's error), the chance that a right prediction's median exceeds it is at most 1e-3
(Markov's inequality on the count of the d_i above it: at least half of them must be). Otherwise
the link is **broken**. The prediction is **lost** when the fitted orbit hits a body on the way,
when an orbit of the covariance's sigma points does (the covariance then reaches a body and is
no Gaussian), or when the predicted covariance spreads more than :data:`LOST_SKY_RAD` (0.1 rad,
5.7 degrees) on the sky, where the linearised angles behind S_i no longer hold.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from datetime import datetime
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import MeasurementError, PropagationError
from cistrack.least_squares.chi_square import chi2_ppf
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.prediction import predict_orbit
from cistrack.least_squares.residual_table import residual_table
from cistrack.least_squares.result import sigma_factor
from cistrack.model.measurement import MeasurementSet

__all__ = ["Rung", "fitted_dynamics", "ladder_rung", "residual_ladder", "ladder_table", "ladder_json", "LINK_TAIL", "LOST_SKY_RAD"]

LINK_TAIL = 1e-3
"""Largest chance that a right prediction is called a broken link (see the module docstring)."""
LOST_SKY_RAD = 0.1
"""Predicted 1-sigma on the sky (rad, largest axis) above which the prediction is lost."""


@dataclass(frozen=True)
class Rung:
    """One earlier arc against the fit.

    start, end : float          first and last observation, TU
    n : int                     observations
    sites : tuple of str        observatories, in order of first appearance
    verdict : str               "consistent", "broken" or "prediction lost"
    why : str                   the reason in words ("" when consistent)
    rms_arcsec, max_arcsec : float   RMS and largest miss on the sky (nan when lost)
    sigmas, max_sigmas : float  median and largest per-observation miss in sigmas of the predicted
                                covariance and the noise (nan when lost)
    sky_sigma_arcsec : float    largest predicted 1-sigma on the sky over the arc (nan when lost)
    """

    start: float
    end: float
    n: int
    sites: tuple
    verdict: str
    why: str = ""
    rms_arcsec: float = float("nan")
    max_arcsec: float = float("nan")
    sigmas: float = float("nan")
    max_sigmas: float = float("nan")
    sky_sigma_arcsec: float = float("nan")

    def broken(self, why: str) -> "Rung":
        """This rung called a broken link for ``why``."""
        return replace(self, verdict="broken", why=why)


def fitted_dynamics(dynamics, fit) -> Any:
    """``dynamics`` with the fit's solve-for parameters (e.g. the area-to-mass ratio) when it
    estimated any; else ``dynamics`` itself."""
    names = tuple(getattr(fit, "parameter_names", ()))
    if not names:
        return dynamics
    return dynamics.with_parameters(**{n: float(v) for n, v in zip(names, fit.parameters)})


def _scaled(fit) -> Any:
    s = sigma_factor(fit.noise_scale)
    return replace(fit, covariance=fit.covariance * s * s) if s > 1.0 else fit


def _misses(model: MeasurementModel, sub: MeasurementSet, states: np.ndarray,
            covs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(miss on the sky (K,) arcsec, d_i (K,), predicted 1-sigma on the sky (K,) rad: the largest
    axis of H P H^T, right ascension times cos(Dec))."""
    r = model.residuals(states)
    h = model.jacobian(states)
    hph = np.einsum("kmi,kij,knj->kmn", h, covs, h)
    s = hph + np.einsum("km,mn->kmn", model.sigmas ** 2, np.eye(model.m))
    d2 = np.einsum("km,km->k", r, np.linalg.solve(s, r[..., None])[..., 0])
    scale = np.ones_like(r)
    radec = np.array([sub.kind_at(i) == "radec" for i in range(len(sub))])
    scale[radec, 0] = np.cos(model.values[radec, 1])                   # RA on the sky: times cos(Dec)
    sky = np.sqrt(np.maximum(np.linalg.eigvalsh(hph * scale[:, :, None] * scale[:, None, :])[:, -1], 0.0))
    table = residual_table(model.times, np.array([sub.site_at(i) for i in range(len(sub))]),
                           np.array([sub.kind_at(i) for i in range(len(sub))]), model.names, model.values,
                           r, model.sigmas, np.zeros(len(sub), dtype=bool))
    return np.sqrt(np.sum(table.o_c ** 2, axis=1)), np.sqrt(np.maximum(d2, 0.0)), sky


def ladder_rung(fit, dynamics, sensor, measurements: MeasurementSet, span) -> Rung:
    """The :class:`Rung` of the rows ``span.rows`` (an :class:`cistrack.fitting.arcs.ArcSpan`) of
    ``measurements`` (times TU) against ``fit`` (a FitResult) propagated by ``dynamics`` (with
    the fit's solve-for parameters); ``sensor`` predicts each row (a site network for several
    sites)."""
    sub = measurements.subset(span.rows)
    dynamics = fitted_dynamics(dynamics, fit)
    base = dict(start=float(sub.times[0]), end=float(sub.times[-1]), n=len(sub), sites=tuple(sub.site_keys()))
    try:
        pred = predict_orbit(_scaled(fit), dynamics, sub.times)
        model = MeasurementModel(sensor, sub)
        miss, d, sky = _misses(model, sub, pred.states, pred.covariances)
    except (PropagationError, MeasurementError, np.linalg.LinAlgError) as exc:
        return Rung(**base, verdict="prediction lost", why=f"the fitted orbit cannot be carried back: {exc}")
    if np.any(pred.linear):
        return Rung(**base, verdict="prediction lost",
                    why="orbits within the covariance hit a body on the way: it is no Gaussian there")
    numbers = dict(rms_arcsec=float(np.sqrt(np.mean(miss ** 2))), max_arcsec=float(miss.max()),
                   sigmas=float(np.median(d)), max_sigmas=float(d.max()),
                   sky_sigma_arcsec=float(sky.max() / units.ARCSEC_RAD))
    if sky.max() > LOST_SKY_RAD:
        return Rung(**base, verdict="prediction lost", **numbers,
                    why=f"the predicted 1-sigma reaches {np.degrees(sky.max()):.3g} degrees on the sky")
    bound = chi2_ppf(1.0 - 0.5 * LINK_TAIL, model.m)
    if np.median(d) ** 2 > bound:
        return Rung(**base, verdict="broken", **numbers,
                    why=f"misses by {np.median(d):.3g} sigma (median; bound {np.sqrt(bound):.3g})")
    return Rung(**base, verdict="consistent", **numbers)


def residual_ladder(fit, dynamics, sensor, measurements: MeasurementSet, spans) -> list[Rung]:
    """One :class:`Rung` per span of ``spans`` (ArcSpans, e.g. the earlier arcs), same order."""
    return [ladder_rung(fit, dynamics, sensor, measurements, s) for s in spans]


def _utc(epoch: datetime, t: float) -> str:
    return units.format_utc(units.tu_to_utc(epoch, t))[:16].replace("T", " ")


def _num(x: float, fmt: str) -> str:
    return "-" if not np.isfinite(x) else format(x, fmt)


def ladder_table(rungs: list[Rung], epoch: datetime) -> str:
    """The ladder as text (at most 120 columns): one line per rung; ``epoch``: t = 0 of the TU times."""
    head = (f"{'from (UTC)':<16}  {'to (UTC)':<16}  {'obs':>4}  {'sites':<12}  {'RMS miss':>9}  {'largest':>9}  "
            f"{'sigmas':>7}  link")
    lines = [head]
    for r in rungs:
        sites = ",".join(r.sites)
        sites = sites if len(sites) <= 12 else sites[:11] + "+"
        lines.append(f"{_utc(epoch, r.start):<16}  {_utc(epoch, r.end):<16}  {r.n:>4}  {sites:<12}  "
                     f"{_num(r.rms_arcsec, '.3g') + chr(34):>9}  {_num(r.max_arcsec, '.3g') + chr(34):>9}  "
                     f"{_num(r.sigmas, '.3g'):>7}  {r.verdict}")
    return "\n".join(lines)


def ladder_json(rungs: list[Rung], epoch: datetime) -> list[dict]:
    """The ladder for ``fit.json`` (its ``arcs`` key): one dict per rung, times in UTC, misses in
    arcsec, sigmas as numbers or null."""
    def val(x: float):
        return float(x) if np.isfinite(x) else None
    return [{"first_utc": units.format_utc(units.tu_to_utc(epoch, r.start)),
             "last_utc": units.format_utc(units.tu_to_utc(epoch, r.end)), "observations": r.n,
             "sites": list(r.sites), "verdict": r.verdict, "why": r.why, "rms_miss_arcsec": val(r.rms_arcsec),
             "largest_miss_arcsec": val(r.max_arcsec), "miss_sigmas_median": val(r.sigmas),
             "miss_sigmas_largest": val(r.max_sigmas), "predicted_sky_sigma_arcsec": val(r.sky_sigma_arcsec)}
            for r in rungs]
