"""The orbit fields of a ``fit.json``, checked before ``cistrack predict`` or ``cistrack export`` use them.

A record edited by hand or by another program must give a clear error naming the file and the
field, never a traceback from numpy or datetime, and never predictions or an OEM full of NaN: the
state six finite numbers, the covariance a finite, symmetric, positive semi-definite 6 x 6 matrix,
the epoch a finite time within about a thousand years of the scenario's epoch, the noise scale
positive (or NaN: undefined), the counts whole numbers, an estimated area-to-mass ratio a finite
value with its finite, symmetric 7 x 7 joint covariance, the arc a table of its first and last
times, and each burn of ``maneuvers`` a finite time up to the fit's epoch with a positive time sigma,
a finite delta-v and its covariance.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.least_squares.burn_search import MAX_BURN_MS  # the largest burn a fit reports, m/s

__all__ = ["check_orbit_fields", "MAX_EPOCH_TU", "MAX_DISTANCE_KM", "MAX_SPEED_KMS"]

MAX_DISTANCE_KM = 3.0e6
"""The farthest fitted position (km; about eight lunar distances): a fit beyond it is not a cislunar
orbit and is not reported as converged (:data:`cistrack.fitting.from_observations.CISLUNAR_LIMIT_KM`)."""
MAX_SPEED_KMS = 100.0
"""The fastest fitted state (km/s in the synodic frame; an object falling to the Earth's surface
from the Moon's distance reaches about 11)."""

MAX_EPOCH_TU = 4.0e3
"""The largest |epoch_tu| accepted (about 47 years from the scenario's epoch: a fit's epoch lies in
its arc, and its exports' frames need the DE421 ephemeris, 1899-2053)."""

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
    _check_epoch_utc(p, record, epoch)
    scale = _number(p, "noise_scale", record.get("noise_scale"))
    if not (math.isnan(scale) or (math.isfinite(scale) and scale > 0.0)):
        raise _fail(p, "noise_scale", "a positive number (NaN: undefined)", scale)
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
    _check_spread(p, record.get("covariance"))
    _check_arc(p, record.get("arc"))
    _check_maneuvers(p, record.get("maneuvers"), epoch)
    _check_determination(p, record.get("determination", {}))


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


def _check_spread(p: Path, cov: Any) -> None:
    """A covariance whose sigmas reach beyond :data:`MAX_DISTANCE_KM` or :data:`MAX_SPEED_KMS` is no fit's."""
    sig = units.state_to_km(np.sqrt(np.diag(np.asarray(cov, dtype=float))))
    if np.max(sig[:3]) > MAX_DISTANCE_KM or np.max(sig[3:]) > MAX_SPEED_KMS:
        raise _fail(p, "covariance", f"a covariance whose sigmas stay within {MAX_DISTANCE_KM:.3g} km and "
                    f"{MAX_SPEED_KMS:g} km/s", f"sigmas {sig.tolist()}")


def _check_arc(p: Path, arc: Any) -> None:
    if not isinstance(arc, dict):
        raise _fail(p, "arc", "a table of the arc's first_tu and last_tu", arc)
    first, last = (_number(p, f"arc.{k}", arc.get(k)) for k in ("first_tu", "last_tu"))
    if not (math.isfinite(first) and math.isfinite(last) and first <= last and abs(last) <= MAX_EPOCH_TU
            and abs(first) <= MAX_EPOCH_TU):
        raise _fail(p, "arc", f"finite first_tu <= last_tu within {MAX_EPOCH_TU:g} TU", arc)


_BURN_NUMBERS = ("t_days", "t_burn_days", "t_burn_sigma_days", "delta_v_ms", "delta_v_sigma_ms")


def _check_epoch_utc(p: Path, record: dict[str, Any], epoch_tu: float) -> None:
    """``epoch_utc``: UTC text, the scenario's epoch (``scenario_epoch_utc``, where given) plus
    ``epoch_tu`` to within a millisecond. An edited one (even 2026-13-45T99:00:00Z) had been exported
    as the OEM's stated fit epoch, its states from the other two."""
    text = record.get("epoch_utc")
    what = "a UTC time as text, the scenario's epoch (scenario_epoch_utc) plus epoch_tu"
    try:
        when = units.parse_utc(text) if isinstance(text, str) else None
        start = record.get("scenario_epoch_utc")
        expected = units.tu_to_utc(units.parse_utc(start), epoch_tu) if isinstance(start, str) else when
    except (ValueError, TypeError, OverflowError):
        raise _fail(p, "epoch_utc", what, text) from None
    if when is None or abs((when - expected).total_seconds()) > 1e-3:
        raise _fail(p, "epoch_utc", what, text)


def _check_maneuvers(p: Path, burns: Any, epoch_tu: float) -> None:
    """Each burn: finite numbers, a positive time sigma, a time up to the fit's epoch, a finite
    delta-v vector (3) and a covariance (3 x 3, symmetric, positive semi-definite)."""
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
        _check_burn_text(p, where, b)
        _array(p, f"{where}.delta_v_vector_ms", b.get("delta_v_vector_ms"), (3,), "3 finite numbers (m/s)")
        _covariance(p, f"{where}.delta_v_covariance_ms2", b.get("delta_v_covariance_ms2"), 3)


def _check_burn_text(p: Path, where: str, b: dict) -> None:
    """A burn's UTC time (quoted in exports' comments) an ISO-8601 time, its gap a time order."""
    utc = b.get("t_burn_utc")
    if utc is not None:
        try:
            units.parse_utc(utc)
        except (TypeError, ValueError):
            raise _fail(p, f"{where}.t_burn_utc", "an ISO-8601 UTC time", utc) from None
    window = b.get("t_burn_window_days")
    if window is not None:
        w = _array(p, f"{where}.t_burn_window_days", window, (2,), "two finite days, the first not after the second")
        if w[0] > w[1]:
            raise _fail(p, f"{where}.t_burn_window_days", "two finite days, the first not after the second", window)


def _check_area_to_mass(p: Path, amr: Any) -> None:
    if amr is None:
        return
    if not isinstance(amr, dict):
        raise _fail(p, "area_to_mass", "a table", amr)
    if not amr.get("estimated"):
        return
    value = _number(p, "area_to_mass.value_m2_kg", amr.get("value_m2_kg"))
    if not math.isfinite(value):
        raise _fail(p, "area_to_mass.value_m2_kg", "a finite number (m^2/kg)", value)
    if "full_covariance" in amr:
        _covariance(p, "area_to_mass.full_covariance", amr["full_covariance"], 7)
