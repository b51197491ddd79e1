"""The orbit fields of a ``fit.json``, checked before ``cistrack predict`` or ``cistrack export`` use them.

A record edited by hand or by another program must give a clear error naming the file and the
field, never a traceback from numpy or datetime, and never predictions or an OEM full of NaN: the
state six finite numbers, the covariance a finite, symmetric, positive semi-definite 6 x 6 matrix,
the epoch a finite time within about a thousand years of the scenario's epoch, its UTC text the
scenario's epoch (``scenario_epoch_utc``) plus ``epoch_tu``, the noise scale positive (or NaN:
undefined) and small enough that the covariance it scales keeps cislunar sigmas, the counts whole
numbers, an estimated area-to-mass ratio a finite value with its sigmas, its six correlations with
the state and its finite, symmetric 7 x 7 joint covariance, the arc a table of its first and last
times (and their UTC) that holds the fit's epoch and spans at most :data:`MAX_ARC_DAYS`, and each burn
of ``maneuvers`` a finite time up to the fit's epoch (its UTC, where given, the same time) with a
positive time sigma, a finite delta-v and its covariance.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.least_squares.burn_search import MAX_BURN_MS  # the largest burn a fit reports, m/s
from cistrack.least_squares.result import sigma_factor

__all__ = ["check_orbit_fields", "covariance_scale", "within_reach", "MAX_EPOCH_TU", "MAX_DISTANCE_KM", "MAX_SPEED_KMS",
           "MAX_ARC_DAYS"]

MAX_DISTANCE_KM = 3.0e6
"""The farthest fitted position (km; about eight lunar distances): a fit beyond it is not a cislunar
orbit and is not reported as converged (:data:`cistrack.fitting.from_observations.CISLUNAR_LIMIT_KM`)."""
MAX_SPEED_KMS = 100.0
"""The fastest fitted state (km/s in the synodic frame; an object falling to the Earth's surface
from the Moon's distance reaches about 11)."""

MAX_EPOCH_TU = 4.0e3
"""The largest |epoch_tu| accepted (about 47 years from the scenario's epoch: a fit's epoch lies in
its arc, and its exports' frames need the DE421 ephemeris, 1899-2053)."""

MAX_ARC_DAYS = 731.0
"""The longest arc (last observation minus first, days) a fit.json may state: two years. No fit of one
cislunar orbit spans more, and an export of a longer one would propagate its 10-minute grid for hours
(an edited ``arc.first_tu`` of -3000 TU, 36 years, had made ``cistrack export`` hang)."""
UTC_TOLERANCE_S = 1e-3
"""How far (seconds) a UTC text of fit.json may lie from the time its TU field and
``scenario_epoch_utc`` give: the rounding of a written time."""
BURN_UTC_TOLERANCE_S = 1.0
"""How far (seconds) a burn's ``t_burn_utc`` may lie from ``scenario_epoch_utc`` plus ``t_burn_days``."""

def within_reach(km: np.ndarray) -> np.ndarray:
    """Whether each state (M, 6) [km, km/s, synodic] lies within :data:`MAX_DISTANCE_KM` of the
    Earth-Moon barycentre and moves slower than :data:`MAX_SPEED_KMS` (each component and the norm):
    the states a fit's files may hold. Returns (M,) bool."""
    km = np.atleast_2d(np.asarray(km, dtype=float))
    pos, vel = km[:, :3], km[:, 3:]
    with np.errstate(over="ignore"):  # a norm of 1e300 is inf, beyond either way
            return ((np.max(np.abs(pos), axis=1) <= MAX_DISTANCE_KM) & (np.linalg.norm(pos, axis=1) <= MAX_DISTANCE_KM)
                & (np.max(np.abs(vel), axis=1) <= MAX_SPEED_KMS) & (np.linalg.norm(vel, axis=1) <= MAX_SPEED_KMS))


_NUMBERS = ("rms", "chi2", "condition_number")
_COUNTS = ("n_used", "n_rejected", "iterations")


def _fail(path: Path, field: str, what: str, value: Any) -> ConfigError:
    shown = repr(value)
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    return ConfigError(f"{path}: field {field!r} must be {what} (got {shown}); the file is not a fit record "
                       "that cistrack wrote: fit the observations again")


def _array(path: Path, field: str, value: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``value`` as a finite float array of ``shape``, else ConfigError naming ``field``."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise _fail(path, field, what, value) from None
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise _fail(path, field, what, value)
    return arr


def _covariance(path: Path, field: str, value: Any, n: int) -> None:
    what = f"a {n} x {n} matrix of finite numbers, symmetric and positive semi-definite"
    cov = _array(path, field, value, (n, n), what)
    scale = float(np.max(np.abs(cov))) or 1.0
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-12 * scale):
        raise _fail(path, field, what + " (it is not symmetric)", value)
    eig = np.linalg.eigvalsh(0.5 * (cov + cov.T))
    if eig[-1] <= 0.0 or eig[0] < -1e-9 * eig[-1]:
        raise _fail(path, field, what + f" (eigenvalues {eig[0]:.3g} to {eig[-1]:.3g})", value)


def _number(path: Path, field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(path, field, "a number", value)
    return float(value)


def covariance_scale(record: dict[str, Any]) -> float:
    """max(1, noise scale)^2 of a fit record (1 when the noise scale is undefined)."""
    s = sigma_factor(record.get("noise_scale", float("nan")))
    return s * s


def check_orbit_fields(path: str | Path, record: dict[str, Any]) -> None:
    """Raise :class:`ConfigError` naming ``path`` and the field when the orbit of ``record`` (a
    ``fit.json`` with a ``state``) is not one a fit writes (module docstring)."""
    p = Path(path)
    km = units.state_to_km(_array(p, "state", record.get("state"), (6,), "6 finite numbers (the synodic state)"))
    far = np.linalg.norm(km[:3]) > MAX_DISTANCE_KM or np.linalg.norm(km[3:]) > MAX_SPEED_KMS
    if far and record.get("converged") is not False:  # a fit refused as not cislunar keeps its state
        raise _fail(p, "state", f"a synodic state within {MAX_DISTANCE_KM:.3g} km of the Earth-Moon barycentre, "
                    f"moving slower than {MAX_SPEED_KMS:g} km/s", record.get("state"))
    _covariance(p, "covariance", record.get("covariance"), 6)
    epoch = _number(p, "epoch_tu", record.get("epoch_tu"))
    if not (math.isfinite(epoch) and abs(epoch) <= MAX_EPOCH_TU):
        raise _fail(p, "epoch_tu", f"a finite time within {MAX_EPOCH_TU:g} TU of the scenario's epoch", epoch)
    start = _scenario_epoch(p, record)
    _check_utc(p, "epoch_utc", record.get("epoch_utc"), "epoch_tu", units.tu_to_utc(start, epoch), UTC_TOLERANCE_S)
    _check_noise_scale(p, record)
    for field in _NUMBERS:
        _number(p, field, record.get(field))
    for field in _COUNTS:
        value = record.get(field)
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise _fail(p, field, "a whole number >= 0", value)
    if not isinstance(record.get("converged"), bool):
        raise _fail(p, "converged", "true or false", record.get("converged"))
    _array(p, "weakest_direction_km", record.get("weakest_direction_km"), (6,), "6 finite numbers")
    _check_area_to_mass(p, record.get("area_to_mass"))
    _check_arc(p, record.get("arc"), epoch, start)
    _check_maneuvers(p, record.get("maneuvers"), epoch, start)
    _check_determination(p, record.get("determination", {}))


def _check_noise_scale(p: Path, record: dict[str, Any]) -> None:
    """Positive or NaN (undefined), and the covariance's sigmas, unscaled and times the noise scale
    (when above 1: :func:`covariance_scale`), within cislunar space: a noise scale of 1e300 had
    made every exported and predicted covariance infinite or NaN."""
    scale = _number(p, "noise_scale", record.get("noise_scale"))
    if not (math.isnan(scale) or (math.isfinite(scale) and scale > 0.0)):
        raise _fail(p, "noise_scale", "a positive number (NaN: undefined)", scale)
    sig = units.state_to_km(np.sqrt(np.diag(np.asarray(record.get("covariance"), dtype=float))))
    if record.get("converged") is False:  # a fit refused as undetermined keeps its wide covariance
        _check_finite_scaled(p, record, sig)
        return
    limits = f"within {MAX_DISTANCE_KM:.3g} km and {MAX_SPEED_KMS:g} km/s"
    if np.max(sig[:3]) > MAX_DISTANCE_KM or np.max(sig[3:]) > MAX_SPEED_KMS:
        raise _fail(p, "covariance", f"a covariance whose sigmas stay {limits}", f"sigmas {sig.tolist()}")
    factor = math.sqrt(covariance_scale(record))
    if np.max(sig[:3]) > MAX_DISTANCE_KM / factor or np.max(sig[3:]) > MAX_SPEED_KMS / factor:
        raise _fail(p, "noise_scale", "a positive number (NaN: undefined) small enough that the covariance scaled "
                    f"by its square (when above 1) keeps its sigmas {limits}", scale)


def _check_finite_scaled(p: Path, record: dict[str, Any], sig: np.ndarray) -> None:
    """The sigmas (km, km/s) of a fit that did not converge, times the noise scale, squared: finite."""
    scaled = sig * math.sqrt(covariance_scale(record))
    with np.errstate(over="ignore"):
        finite = bool(np.all(np.isfinite(scaled * scaled)))
    if not finite:
        raise _fail(p, "covariance", "a covariance whose sigmas, scaled by the noise scale, stay finite",
                    f"sigmas {sig.tolist()}")


def _scenario_epoch(p: Path, record: dict[str, Any]):
    """``scenario_epoch_utc``, the UTC time the record's TU and days times count from."""
    text = record.get("scenario_epoch_utc")
    what = "a UTC time as text (the scenario's epoch, which the record's _tu and _days times count from)"
    if not isinstance(text, str):
        raise _fail(p, "scenario_epoch_utc", what, text)
    try:
        return units.parse_utc(text)
    except (ValueError, TypeError, OverflowError):
        raise _fail(p, "scenario_epoch_utc", what, text) from None


def _check_utc(p: Path, field: str, text: Any, source: str, expected, tolerance_s: float) -> None:
    """``text`` (the UTC field ``field``) a UTC time within ``tolerance_s`` of ``expected``, the time
    its field ``source`` (TU or days) gives from ``scenario_epoch_utc``: exports quote it as that time.
    An edited one (even 2026-13-45T99:00:00Z) had been exported as the OEM's stated time."""
    what = (f"a UTC time as text, the scenario's epoch (scenario_epoch_utc) plus {source}: "
            f"{units.format_utc(expected)} to within {tolerance_s:g} s")
    try:
        when = units.parse_utc(text) if isinstance(text, str) else None
    except (ValueError, TypeError, OverflowError):
        when = None
    if when is None or abs((when - expected).total_seconds()) > tolerance_s:
        raise _fail(p, field, what, text)


def _check_determination(p: Path, det: Any) -> None:
    """The verdict's table (absent for fits that made none): its horizons are days >= 0, or null
    (never left within the grid, or not measured); exports and predictions warn by them."""
    if not isinstance(det, dict):
        raise _fail(p, "determination", "a table (the fit's verdict)", det)
    for field in ("horizon_days", "covariance_horizon_days"):
        value = det.get(field)
        if value is not None and not (not isinstance(value, bool) and isinstance(value, (int, float))
                                      and math.isfinite(value) and value >= 0.0):
            raise _fail(p, f"determination.{field}", "a number of days >= 0, or null", value)


def _check_arc(p: Path, arc: Any, epoch_tu: float, start) -> None:
    """The arc: finite first_tu <= the fit's epoch <= last_tu (the fit epoch is one of its
    observations), at most :data:`MAX_ARC_DAYS` apart, and first_utc and last_utc the same times."""
    if not isinstance(arc, dict):
        raise _fail(p, "arc", "a table of the arc's first_tu and last_tu", arc)
    first, last = (_number(p, f"arc.{k}", arc.get(k)) for k in ("first_tu", "last_tu"))
    if not (math.isfinite(first) and math.isfinite(last) and first <= last and abs(last) <= MAX_EPOCH_TU
            and abs(first) <= MAX_EPOCH_TU):
        raise _fail(p, "arc", f"finite first_tu <= last_tu within {MAX_EPOCH_TU:g} TU", arc)
    slack = 1e-9 * max(1.0, abs(epoch_tu))
    if not first - slack <= epoch_tu <= last + slack:
        raise _fail(p, "arc", f"first_tu <= epoch_tu ({epoch_tu:.9g}) <= last_tu: the fit's epoch is one of its "
                    "observations", {"first_tu": first, "last_tu": last})
    if float(units.tu_to_days(last - first)) > MAX_ARC_DAYS:
        raise _fail(p, "arc.first_tu", f"the first observation at most {MAX_ARC_DAYS:g} days before the last "
                    f"(last_tu {last:.9g}; no fit of one orbit spans more)", first)
    for k in ("first", "last"):
        _check_utc(p, f"arc.{k}_utc", arc.get(f"{k}_utc"), f"arc.{k}_tu", units.tu_to_utc(start, arc[f"{k}_tu"]), UTC_TOLERANCE_S)


_BURN_NUMBERS = ("t_days", "t_burn_days", "t_burn_sigma_days", "delta_v_ms", "delta_v_sigma_ms")


def _check_maneuvers(p: Path, burns: Any, epoch_tu: float, start) -> None:
    """Each burn: finite numbers, a positive time sigma, a time up to the fit's epoch (its UTC, where
    given, the same time), a finite delta-v vector (3) and a covariance (3 x 3, symmetric, positive
    semi-definite)."""
    if burns is None:
        return
    if not isinstance(burns, list):
        raise _fail(p, "maneuvers", "a list of burns", burns)
    for k, b in enumerate(burns):
        where = f"maneuvers[{k}]"
        if not isinstance(b, dict):
            raise _fail(p, where, "a table", b)
        values = {n: _number(p, f"{where}.{n}", b.get(n)) for n in _BURN_NUMBERS}
        if not all(math.isfinite(v) for v in values.values()) or min(
                values[n] for n in ("t_burn_sigma_days", "delta_v_ms", "delta_v_sigma_ms")) < 0.0:
            raise _fail(p, where, "finite times, and non-negative sigmas and sizes", b)
        if not (values["t_burn_sigma_days"] > 0.0 and math.isfinite(values["t_burn_days"])
                and values["t_burn_days"] <= float(units.tu_to_days(epoch_tu)) + 1e-9):
            raise _fail(p, f"{where}.t_burn_days", "a finite time up to the fit's epoch, with a positive sigma", b)
        if values["delta_v_ms"] > MAX_BURN_MS:
            raise _fail(p, f"{where}.delta_v_ms", f"a burn of at most {MAX_BURN_MS:g} m/s (larger is no burn a fit "
                        "reports)", values["delta_v_ms"])
        _check_burn_text(p, where, b, units.tu_to_utc(start, float(units.days_to_tu(values["t_burn_days"]))))
        _array(p, f"{where}.delta_v_vector_ms", b.get("delta_v_vector_ms"), (3,), "3 finite numbers (m/s)")
        _covariance(p, f"{where}.delta_v_covariance_ms2", b.get("delta_v_covariance_ms2"), 3)


def _check_burn_text(p: Path, where: str, b: dict, when) -> None:
    """A burn's UTC time (quoted in exports' comments), where given, ``when`` (its t_burn_days) to
    within a second; its gap a time order."""
    if b.get("t_burn_utc") is not None:
        _check_utc(p, f"{where}.t_burn_utc", b["t_burn_utc"], "t_burn_days", when, BURN_UTC_TOLERANCE_S)
    window = b.get("t_burn_window_days")
    if window is not None:
        w = _array(p, f"{where}.t_burn_window_days", window, (2,), "two finite days, the first not after the second")
        if w[0] > w[1]:
            raise _fail(p, f"{where}.t_burn_window_days", "two finite days, the first not after the second", window)


def _check_area_to_mass(p: Path, amr: Any) -> None:
    """An estimated C_R A/m: a finite value, finite sigmas >= 0 (exports quote the scaled one), six
    correlations with the state from -1 to 1 and, where given, its 7 x 7 joint covariance."""
    if amr is None:
        return
    if not isinstance(amr, dict):
        raise _fail(p, "area_to_mass", "a table", amr)
    if not amr.get("estimated"):
        return
    value = _number(p, "area_to_mass.value_m2_kg", amr.get("value_m2_kg"))
    if not math.isfinite(value):
        raise _fail(p, "area_to_mass.value_m2_kg", "a finite number (m^2/kg)", value)
    for field in ("sigma_m2_kg", "sigma_scaled_m2_kg"):
        sigma = amr.get(field)
        if isinstance(sigma, bool) or not isinstance(sigma, (int, float)) or not (math.isfinite(sigma) and sigma >= 0):
            raise _fail(p, f"area_to_mass.{field}", "a finite number >= 0 (m^2/kg)", sigma)
    what = "6 finite numbers from -1 to 1 (the correlations with x, y, z, vx, vy, vz)"
    corr = _array(p, "area_to_mass.correlations_with_state", amr.get("correlations_with_state"), (6,), what)
    if np.any(np.abs(corr) > 1.0 + 1e-9):
        raise _fail(p, "area_to_mass.correlations_with_state", what, amr.get("correlations_with_state"))
    if "full_covariance" in amr:
        _covariance(p, "area_to_mass.full_covariance", amr["full_covariance"], 7)
