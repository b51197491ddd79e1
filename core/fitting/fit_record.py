"""The files ``cistrack fit`` writes beside the filter run's results, and reading them back.

- ``fit.json``: the fitted state and covariance at the fit epoch (synodic frame of the
  scenario's dynamics: exact nondimensional values and km, km/s), the epoch in UTC and TU, the
  arc, RMS, chi-square, assumed and estimated noise, counts, condition number, messages, the
  filter run it started from and the settings; with ``--set fit.area_to_mass=solve|auto`` also
  ``area_to_mass``: the radiation pressure's C_R A/m (m^2/kg), its sigma, its correlations with
  the state and the 7x7 covariance, or why "auto" did not estimate it;
- ``residuals.csv``: one row per observation: time UTC, site, O - C (RA x cos(Dec) and Dec in
  arcsec for RA/Dec), normalised residuals, chi-square, rejected;
- ``residuals-<site>.png`` / ``.svg``: the residual plot of each site
  (:mod:`cistrack.fitting.residual_plots`);
- ``lov.csv`` with ``--set fit.lov=N``: the line of variations (:mod:`cistrack.least_squares.line_of_variations`),
  one row per point: sigma, chi-square and its rise, the state (km, km/s, synodic), its
  distance from the fitted state and its departure from the straight line x* + sigma v (km); its
  summary is ``line_of_variations`` in ``fit.json``.

Observations that determine no orbit (one lone tracklet) get a ``fit.json`` without a state:
``converged`` false, ``failure`` the reason in words, and ``undetermined``: the same sentence, the
tracklet's place and rates on the sky and the admissible region's ranges and range rates.

Each file is written whole or not at all (temporary file, then rename).
"""
from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, ConfigError
from cistrack.fitting.fit_record_check import check_orbit_fields
from cistrack.least_squares.result import sigma_factor
from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.strict_json import finite_or_null

__all__ = ["write_fit_outputs", "read_fit_record", "UNDEFINED_NUMBERS", "FIT_RECORD", "RESIDUALS", "LOV", "noise_summary",
           "area_to_mass_record", "area_to_mass_summary", "outputs_text", "unsound_reason"]

FIT_RECORD = "fit.json"
RESIDUALS = "residuals.csv"
LOV = "lov.csv"
_FORMAT = "cistrack-fit"


def _utc(scen, t: float) -> str:
    return units.format_utc(units.tu_to_utc(scen.epoch, float(t)))


def noise_summary(measurements, result) -> dict[str, dict[str, float]]:
    """Assumed (median of the observations' sigmas) and estimated (assumed x noise scale) noise
    per component, arcsec on the sky (RA x cos(Dec)), with the post-fit RMS of each column."""
    names = result.residuals.column_names()
    sig = np.asarray(measurements.sigmas[:, :len(names)], dtype=float) / units.ARCSEC_RAD
    kinds = np.array([measurements.kind_at(i) for i in range(len(measurements))])
    if sig.shape[1] >= 2:
        radec = kinds == "radec"
        sig[radec, 0] *= np.cos(measurements.values[radec, 1])
    rms = result.residuals.rms()
    out = {}
    for j, name in enumerate(names):
        assumed = float(np.median(sig[:, j]))
        out[name] = {"assumed": assumed, "estimated": assumed * float(result.noise_scale),
                     "post_fit_rms": float(rms[j])}
    return out


def unsound_reason(messages) -> str:
    """Why a least-squares fit with ``messages`` (its messages in order, str) is not reported as
    converged: the last verdict that judged it unsound ("not a clean fit: ...", "not a cislunar
    orbit: ...", ...), else "the least squares did not converge (" its first two messages ")"."""
    messages = [str(m) for m in messages]
    verdict = [m for m in messages if m.startswith("not a ")]  # a converged least squares judged unsound
    if verdict:
        return verdict[-1]
    return "the least squares did not converge (" + "; ".join(messages[:2]) + ")"


def _options_record(options, reject_fraction: float | None = None) -> dict[str, Any]:
    """The fit options as recorded: all but ``sensor_steps`` (``area_to_mass`` "off" too, which had
    been left out, so that a fit told "off" read as one that was never told);
    ``max_reject_fraction`` the share the fit's least squares applied (``reject_fraction`` when
    given: from the ranging IOD's orbit, where it had recorded the setting's 0.5 beside the 0.1
    applied, probe I5)."""
    record = {k: getattr(options, k) for k in options.__dataclass_fields__ if k != "sensor_steps"}
    if reject_fraction is not None:
        record["max_reject_fraction"] = reject_fraction
    return record


def area_to_mass_record(result) -> dict[str, Any] | None:
    """``fit.json``'s ``area_to_mass``: the estimate of C_R A/m (m^2/kg), its one sigma (of the
    stated weights, and times the noise scale when that exceeds 1), its correlations with the
    state (x, y, z, vx, vy, vz) and how "auto" decided; None when it was neither estimated nor
    decided on."""
    from cistrack.least_squares.options import AREA_TO_MASS

    est = result.parameter(AREA_TO_MASS)
    if est is None and not result.area_to_mass_decision:
        return None
    out: dict[str, Any] = {"estimated": est is not None, "decision": result.area_to_mass_decision,
                           "parameter": "C_R A/m of the cannonball radiation pressure, m^2/kg"}
    if est is not None:
        j = result.parameter_names.index(AREA_TO_MASS)
        scale = sigma_factor(result.noise_scale)
        out.update({"value_m2_kg": est[0], "sigma_m2_kg": est[1], "sigma_scaled_m2_kg": est[1] * scale,
                    "correlations_with_state": [float(c) for c in result.parameter_correlations[j]],
                    "full_covariance": np.asarray(result.full_covariance).tolist()})
    return out


def area_to_mass_summary(result) -> list[str]:
    """The summary lines on the area-to-mass ratio of a fit: its estimate, sigma and correlations
    with the state, or why "auto" did not estimate it; none when it was not asked for."""
    amr = area_to_mass_record(result)
    if amr is None:
        return []
    if not amr["estimated"]:
        return [f"  area-to-mass ratio (C_R A/m): {amr['decision']}"]
    corr = " / ".join(f"{c:+.2f}" for c in amr["correlations_with_state"])
    how = f" ({amr['decision']})" if amr["decision"] else ""
    return [f"  area-to-mass ratio (C_R A/m): {amr['value_m2_kg']:.4g} +- {amr['sigma_scaled_m2_kg']:.2g} m^2/kg "
            f"(1 sigma, times the noise scale when above 1){how}",
            f"    its correlations with x / y / z / vx / vy / vz at the fit epoch: {corr}"]


def _fit_dict(one, obs) -> dict[str, Any]:
    scen, r = one.scenario, one.result
    ms = one.run.context.measurements if one.run is not None else None
    data: dict[str, Any] = {
        "format": _FORMAT, "version": 1, "designation": one.designation,
        "files": [str(f) for f in obs.files], "weights": list(one.notes),
        "scenario_epoch_utc": units.format_utc(scen.epoch) if scen is not None else None,
        "settings": {"epoch": one.choices.epoch, "prior": one.choices.prior,
                     "lov": "auto" if one.choices.lov is None else one.choices.lov,
                     "options": _options_record(one.choices.options, getattr(one, "reject_fraction", None))},
        "converged": bool(r.converged) if r is not None else False,
        "failure": one.failure,
        "least_squares_start": one.start or ("none: no orbit" if getattr(one, "undetermined", None)
                                             else "the filter's final estimate"),
    }
    if ms is not None and len(ms):
        data["arc"] = {"first_utc": _utc(scen, ms.times[0]), "last_utc": _utc(scen, ms.times[-1]),
                       "first_tu": float(ms.times[0]), "last_tu": float(ms.times[-1]),
                       "sites": ms.site_keys(), "n_observations": int(len(ms))}
    if one.run is not None:
        s = one.run.summary
        belief = one.run.context.filter.belief
        data["filter"] = {"name": scen.components["filter"].name, "iod": scen.components["iod"].name,
                          "status": s.status, "failure": s.failure,
                          "verdict": getattr(s.verdict, "kind", None), "verdict_reason": getattr(s.verdict, "reason", None),
                          "final_epoch_utc": _utc(scen, belief.epoch),
                          "n_observations": int(getattr(one, "filter_rows", 0) or (len(ms) if ms is not None else 0))}
    if getattr(one, "undetermined", None):
        data["undetermined"] = one.undetermined
    if r is None:
        return data
    data.update({
        "frame": "synodic frame of the scenario's dynamics (barycentric Earth-Moon rotating), km and km/s",
        "epoch_utc": _utc(scen, r.epoch), "epoch_tu": float(r.epoch),
        "state": [float(v) for v in r.state], "covariance": np.asarray(r.covariance).tolist(),
        "state_km": [float(v) for v in r.state_km], "covariance_km": np.asarray(r.covariance_km).tolist(),
        "sigmas_km": [float(v) for v in r.sigmas_km],
        "rms": float(r.rms), "chi2": float(r.chi2), "noise_scale": float(r.noise_scale),
        "n_used": int(r.n_used), "n_rejected": int(r.n_rejected), "iterations": int(r.iterations),
        "condition_number": float(r.condition_number),
        "weakest_direction_km": [float(v) for v in r.weakest_direction_km],
        "unobservable": bool(r.unobservable), "rejection_threshold": float(r.rejection_threshold),
        "noise_arcsec": noise_summary(ms, r), "messages": list(r.messages),
    })
    amr = area_to_mass_record(r)
    if amr is not None:
        data["area_to_mass"] = amr
    if one.lov:
        from cistrack.least_squares.line_of_variations import line_summary

        data["line_of_variations"] = {**line_summary(one.lov, r), "points": len(one.lov), "file": LOV}
    data.update(_context_record(one))
    return data


def _context_record(one) -> dict[str, Any]:
    """How well the orbit is determined, the earlier arcs against it, its events and its burns,
    where known."""
    out: dict[str, Any] = {"maneuvers": list(getattr(one, "maneuvers", None) or [])}
    det = getattr(one, "determination", None)
    if det is not None:
        out["determination"] = det.as_dict()
    arcs = getattr(one, "arcs", None)
    if arcs is not None:
        from cistrack.fitting.residual_ladder import ladder_json

        out["arcs"] = ladder_json(arcs.ladder, one.scenario.epoch)
    events = getattr(one, "events", None)
    if events is not None:
        from cistrack.least_squares.events import FIT_EVENT_DAYS

        out["events"] = {"days": FIT_EVENT_DAYS, "list": [e.as_dict() for e in events]}
    gaps = getattr(one, "burn_sensitivity", None)
    if gaps is not None:
        out["burn_sensitivity"] = burn_sensitivity_record(gaps, one.scenario.epoch)
    return out


def burn_sensitivity_record(gaps, epoch) -> dict[str, Any]:
    """``fit.json``'s ``burn_sensitivity``: ``sigmas`` (a burn that raises the refitted chi-square by
    less than its square would not show) and, per gap between observing sessions, its ``start_utc``
    and ``end_utc`` (the observations either side), ``largest_hidden_ms`` (m/s; null: a burn there
    is not determined at all), and that burn's ``t_worst_utc`` and ``direction_synodic`` (a unit
    vector, sign arbitrary) (:mod:`cistrack.least_squares.burn_sensitivity`)."""
    from cistrack.least_squares.burn_sensitivity import HIDDEN_SIGMAS

    def utc(t: float) -> str:
        return units.format_utc(units.tu_to_utc(epoch, t))

    return {"sigmas": HIDDEN_SIGMAS, "gaps": [
        {"start_utc": utc(g.start), "end_utc": utc(g.end),
         "largest_hidden_ms": g.largest_hidden_ms if np.isfinite(g.largest_hidden_ms) else None,
         "t_worst_utc": utc(g.t_worst), "direction_synodic": [float(v) for v in g.direction]} for g in gaps]}


def _lov_csv(points, fit) -> str:
    from cistrack.least_squares.line_of_variations import weakest_direction
    from cistrack.least_squares.observability import km_apart, to_km

    v = weakest_direction(fit.covariance)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["sigma", "chi2", "delta_chi2", "x_km", "y_km", "z_km", "vx_kms", "vy_kms", "vz_kms",
                "offset_km", "departure_km"])
    for p in points:
        km = to_km(p.state)
        w.writerow([repr(float(p.sigma)), repr(float(p.chi2)), repr(float(p.chi2 - fit.chi2)),
                    *[repr(float(c)) for c in km],
                    repr(km_apart(p.state, fit.state)), repr(km_apart(p.state, fit.state + p.sigma * v))])
    return buf.getvalue()


def _residuals_csv(scen, table) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    cols = [c.replace("declination", "dec") for c in table.column_names()]
    w.writerow(["utc", "site", *cols, *[f"norm_{c.rsplit('_', 1)[0]}" for c in cols], "chi2", "rejected"])
    for i in range(len(table)):
        w.writerow([_utc(scen, table.times[i]), table.sites[i],
                    *[repr(float(v)) for v in table.o_c[i]], *[repr(float(v)) for v in table.normalised[i]],
                    repr(float(table.chi2[i])), "true" if table.rejected[i] else "false"])
    return buf.getvalue()


UNDEFINED_NUMBERS = ("rms", "chi2", "noise_scale", "condition_number", "rejection_threshold")
"""Numbers of ``fit.json`` that may be undefined (NaN) or unbounded (infinite), written as null
(strict JSON has neither) and read back as NaN."""


def _json_default(v: Any) -> Any:
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"not JSON serialisable: {type(v).__name__}")


def write_fit_outputs(one, obs) -> list[Path]:
    """Write ``fit.json`` (always, also for a failed fit), and with a fit ``residuals.csv``, the
    residual plots and ``lov.csv`` into ``one.directory``; returns the paths written.

    ``fit.json`` is written last, so that it exists only beside every other file of the fit. When a
    file cannot be written (a full disk) the files of this fit written so far are removed and
    CistrackError names the file: the directory then holds no ``fit.json``, so nothing reads it
    as a finished fit."""
    d = Path(one.directory)
    (d / FIT_RECORD).unlink(missing_ok=True)  # an older fit's record never describes these files
    written: list[Path] = []
    target = d / FIT_RECORD
    try:
        for target, write in _artefacts(one, obs, d):
            written += write(target)
    except OSError as exc:
        for p in written:
            p.unlink(missing_ok=True)
        raise CistrackError(f"{exc.filename or target}: cannot write the fit's results ({exc.strerror or exc}); no {FIT_RECORD} "
                            f"was written, so {d} does not hold a finished fit: make room and run "
                            "'cistrack fit' again") from None
    return written


def outputs_text(one) -> str:
    """The files :func:`write_fit_outputs` writes for ``one``, in words ("fit.json" alone when the fit
    has no orbit: no residuals, plots or line of variations)."""
    names = [RESIDUALS, "the residual plots"] if one.result is not None else []
    names += [LOV] if one.result is not None and one.lov else []
    names = [FIT_RECORD, *names]
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _artefacts(one, obs, d: Path) -> list[tuple[Path, Callable[[Path], list[Path]]]]:
    """(path, writer) of each file of the fit, ``fit.json`` last; a writer returns the files it wrote
    (the residual plots: every site's, named by an OSError's filename when one fails)."""
    from cistrack.fitting.residual_plots import plot_residuals

    out = []
    if one.result is not None:
        out.append((d / RESIDUALS, _text_file(_residuals_csv(one.scenario, one.result.residuals))))
        out.append((d, lambda _d: plot_residuals(d, one.result.residuals, one.scenario.epoch, one.designation)))
    if one.result is not None and one.lov:
        out.append((d / LOV, _text_file(_lov_csv(one.lov, one.result))))
    record = json.dumps(finite_or_null(_fit_dict(one, obs)), indent=1, default=_json_default, allow_nan=False)
    return out + [(d / FIT_RECORD, _text_file(record + "\n"))]


def _text_file(text: str) -> Callable[[Path], list[Path]]:
    """A writer of ``text`` to its path, whole or not at all; its OSError names that path."""
    def write(path: Path) -> list[Path]:
        try:
            write_text_atomic(path, text)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        return [path]
    return write


def read_fit_record(run_dir: str | Path) -> dict[str, Any]:
    """The ``fit.json`` of a fit directory; ConfigError naming the file when absent or unreadable,
    or naming the field when its orbit is not one a fit writes
    (:func:`cistrack.fitting.fit_record_check.check_orbit_fields`)."""
    p = Path(run_dir) / FIT_RECORD
    try:
        data = json.loads(p.read_text())
    except FileNotFoundError:
        raise ConfigError(f"{run_dir}: not a fit directory (no {FIT_RECORD}); run 'cistrack fit FILE --out DIR' "
                          "first") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{p}: cannot be read ({exc})") from None
    except RecursionError:
        raise ConfigError(f"{p}: cannot be read (nested deeper than a fit record ever is)") from None
    if not isinstance(data, dict) or data.get("format") != _FORMAT:
        raise ConfigError(f"{p}: not a cistrack fit record (no \"format\": \"{_FORMAT}\")")
    for key in UNDEFINED_NUMBERS:
        if key in data and data[key] is None:
            data[key] = math.nan
    if "state" in data:
        check_orbit_fields(p, data)
    return data
