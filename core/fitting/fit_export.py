"""Exporting a fitted orbit: ``cistrack export FIT_DIR --format oem [--predict DAYS]``.

The state and covariance of ``fit.json`` are propagated with :func:`cistrack.least_squares.prediction.predict_orbit`
(the covariance by the unscented transform: 13 orbits through the nonlinear dynamics, or with
``covariance='linear'`` by the dynamics' transition matrices) to a regular grid of
:data:`GRID_MINUTES` over the arc (from the first observation, floored to a whole minute, to the
first grid point at or after the last one) and, with ``predict_days``, on beyond the arc; they are
carried into the sensor's inertial frame like a run's estimates and written by the registered
exporter: an OEM gets every grid point with its covariance, OBJECT_NAME and OBJECT_ID from the
designation and Lagrange interpolation keywords; an OPM the state at the fit epoch.

With an estimated area-to-mass ratio (``fit.json``'s ``area_to_mass``) the states are integrated
with it and the covariance is carried from the joint covariance of state and ratio
(:func:`cistrack.least_squares.area_to_mass.joint_covariances`: sigma points of both, each orbit
with its own ratio), not from the state's alone with the ratio held at its estimate: on a 10-day
DRO arc (A/m 0.0105 +- 0.0058 m^2/kg) states and ratios drawn from the joint covariance had a
mean Mahalanobis^2 of 732 under the held-ratio covariance 10 days after the fit epoch, 5.9 under
the joint one (tests/fit/test_export_parameter_covariance.py).

The covariance exported is the fit's (the inverse normal matrix of the stated weights) times
:func:`covariance_scale`: the noise scale squared when the post-fit residuals exceed the stated
noise (weights too optimistic, e.g. a format's default), 1 otherwise, so that the covariance is
never smaller than the residuals say it should be.

A fit that did not converge (or whose filter run gave no estimate) is refused unless ``force``,
and then the file says why in a COMMENT.
"""
from __future__ import annotations

import csv
import dataclasses
import math
import os
import warnings
from dataclasses import dataclass
from datetime import timedelta
from pathlib import Path
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, ConfigError, PropagationError, StateError
from cistrack.fitting.fit_record import read_fit_record, unsound_reason
from cistrack.fitting.fit_record_check import covariance_scale
from cistrack.least_squares.area_to_mass import joint_covariances
from cistrack.least_squares.events import prediction_end
from cistrack.least_squares.line_of_variations import REACH_DELTA_CHI2, widened_to_hold
from cistrack.least_squares.prediction import COVARIANCE_METHODS, predict_orbit
from cistrack.least_squares.residual_table import residual_table
from cistrack.least_squares.result import FitResult, noise_scale_text
from cistrack.least_squares.trajectory import ensemble_arc_states
from cistrack.plugin.registry import Registry, default_registry
from cistrack.results.export_file import PYTHON_EXPORT_WORDS, ExportWords, write_export
from cistrack.results.dir_lock import check_no_writer, check_still_as_read, results_stamp
from cistrack.results.estimates import KM_SCALE, Estimates
from cistrack.results.inertial_frame import to_inertial

__all__ = ["export_fit", "FitExportOptions", "fit_refusal", "covariance_doubt", "fit_grid", "covariance_scale",
           "is_fit_directory", "GRID_MINUTES", "INTERPOLATION_DEGREE", "prediction_warnings", "line_states",
           "after_last_burn", "BURN_MARGIN_SIGMAS", "line_drawn_short", "check_scenario_epoch",
           "refuse_non_finite", "checked_horizon_days", "beyond_checked_horizon"]

GRID_MINUTES = 10.0
"""Spacing of the exported states, minutes."""
INTERPOLATION_DEGREE = 7
"""Lagrange degree recommended to a reader of the OEM (8 points span 70 minutes of the grid)."""
MAX_PREDICT_DAYS = 365.0
"""Longest prediction span accepted, days."""


def is_fit_directory(run_dir: str | Path) -> bool:
    """Whether ``run_dir`` holds a ``fit.json`` (written by ``cistrack fit``)."""
    return (Path(run_dir) / "fit.json").is_file()


def fit_refusal(record: dict[str, Any]) -> str | None:
    """Why the fit of ``record`` (a ``fit.json``) should not be exported without ``force``."""
    if "state" not in record:
        return "it has no fitted orbit (" + (record.get("failure") or "the fit was not made") + ")"
    if not record.get("converged"):
        why = unsound_reason(record.get("messages", []))
        return f"the fit is {why}" if why.startswith("not a ") else why
    return None


def covariance_doubt(record: dict[str, Any]) -> str | None:
    """What the fit's line of variations (``record["line_of_variations"]``, when drawn) says against
    its covariance: "bends" (it leaves the covariance's straight line), "unfollowed" (its first fits
    failed: nothing checked), or None (straight, or not drawn)."""
    lov = record.get("line_of_variations")
    if not isinstance(lov, dict) or lov.get("linear", True):
        return None
    return "bends" if lov.get("followed", True) else "unfollowed"


def _result(record: dict[str, Any]) -> FitResult:
    """A FitResult holding the record's state, covariance (times :func:`covariance_scale`) and
    epoch: what prediction needs."""
    empty = residual_table(np.zeros(0), np.zeros(0, dtype=str), np.zeros(0, dtype=str), ("a", "b"),
                           np.zeros((0, 2)), np.zeros((0, 2)), np.ones((0, 2)), np.zeros(0, dtype=bool))
    scale = covariance_scale(record)
    cov = np.asarray(record["covariance"], dtype=float) * scale
    return FitResult(state=np.asarray(record["state"], dtype=float), covariance=cov, **_solve_for_fields(record, scale),
                     epoch=float(record["epoch_tu"]), residuals=empty, rms=float(record["rms"]), chi2=float(record["chi2"]),
                     n_used=int(record["n_used"]), n_rejected=int(record["n_rejected"]),
                     iterations=int(record["iterations"]), converged=bool(record["converged"]),
                     condition_number=float(record["condition_number"]),
                     weakest_direction_km=np.asarray(record["weakest_direction_km"], dtype=float),
                     noise_scale=float(record["noise_scale"]))


def _solve_for_fields(record: dict[str, Any], scale: float) -> dict[str, Any]:
    """The FitResult fields of the parameters the fit estimated with the state (the area-to-mass
    ratio): names, values and the joint covariance (times ``scale``); none when it estimated none."""
    amr = _estimated_area_to_mass(record)
    if amr is None or "full_covariance" not in amr:
        return {}
    return {"parameter_names": ("area_to_mass_m2_kg",), "parameters": np.array([float(amr["value_m2_kg"])]),
            "full_covariance": np.asarray(amr["full_covariance"], dtype=float) * scale}


def fit_grid(first_tu: float, last_tu: float, epoch, predict_days: float = 0.0,
             minutes: float = GRID_MINUTES) -> tuple[np.ndarray, int]:
    """Grid times (TU since ``epoch``) every ``minutes`` from the first observation floored to a
    whole minute through the last one, then ``predict_days`` on; and the number of grid points
    that cover the arc. The grid is one of UTC labels (whole minutes apart on the clock): a step
    across a leap second is one second longer in elapsed time."""
    first_utc = units.tu_to_utc(epoch, first_tu).replace(second=0, microsecond=0)
    start = (first_utc - epoch).total_seconds() / units.TU_S
    step = minutes * 60.0 / units.TU_S
    n_arc = int(math.ceil((last_tu - start) / step - 1e-9)) + 1
    n_all = n_arc + int(math.ceil(predict_days * 1440.0 / minutes - 1e-9))
    grid = start + step * np.arange(n_all)
    leaps = units.grid_leap_seconds(epoch, first_utc, timedelta(minutes=minutes), n_all)
    return (grid, n_arc) if leaps is None else (grid + leaps / units.TU_S, n_arc)


BURN_MARGIN_SIGMAS = 3.0
"""The states of a fit with burns start this many of the last burn's time sigmas after it."""


def _burns(record: dict[str, Any]) -> tuple[list[dict], dict | None]:
    """(the ``maneuvers`` entries of fit.json that give a burn time, the latest of them or None)."""
    burns = [m for m in record.get("maneuvers") or [] if isinstance(m, dict) and "t_burn_days" in m]
    return burns, max(burns, key=lambda m: float(m["t_burn_days"])) if burns else None


def after_burns_tu(record: dict[str, Any]) -> float | None:
    """The first time (TU) the fitted orbit describes the object: the last burn of
    ``record["maneuvers"]`` plus :data:`BURN_MARGIN_SIGMAS` of its time's sigma, never past the fit
    epoch; None for a fit without burns."""
    burns, last = _burns(record)
    if not burns:
        return None
    start = float(units.days_to_tu(float(last["t_burn_days"])
                                   + BURN_MARGIN_SIGMAS * float(last.get("t_burn_sigma_days") or 0.0)))
    return min(start, float(record["epoch_tu"]))


def after_last_burn(record: dict[str, Any], times: np.ndarray, n_arc: int) -> tuple[np.ndarray, int]:
    """``times`` (K,) TU and ``n_arc`` (those covering the arc) without the times before the last
    burn of ``record["maneuvers"]`` plus :data:`BURN_MARGIN_SIGMAS` of its time's sigma (never past
    the fit epoch): the fitted orbit is the one flown after the burns, and before them the object
    was elsewhere. Unchanged for a fit without burns."""
    start = after_burns_tu(record)
    if start is None:
        return times, n_arc
    keep = times >= start - 1e-12
    if not np.any(keep[:n_arc]):  # the fit epoch lies past the grid's arc part: start at the first time after it
        keep = times >= times[min(int(np.searchsorted(times, start)), times.size - 1)]
    return times[keep], int(np.count_nonzero(keep[:n_arc]))


def _scenario(d: Path, reg: Registry, record: dict[str, Any] | None = None):
    """The fit's scenario (``scenario.toml``); with ``record`` (its fit.json), checked to count from
    the epoch the record's times count from (:func:`check_scenario_epoch`)."""
    from cistrack.scenario.loading import recorded_scenario

    p = d / "scenario.toml"
    try:
        scen = recorded_scenario(p, reg)
    except FileNotFoundError:
        raise ConfigError(f"{d}: not a fit directory (no scenario.toml); run 'cistrack fit FILE --out DIR' first") from None
    if record is not None:
        check_scenario_epoch(d, record, scen)
    return scen


def check_scenario_epoch(d: str | Path, record: dict[str, Any], scen) -> None:
    """Refuse (ConfigError naming both files) a fit directory ``d`` whose ``scenario.toml`` epoch is
    not fit.json's ``scenario_epoch_utc`` (to a millisecond): the fit's TU times count from the latter,
    and an edited scenario.toml had silently shifted every exported state and prediction."""
    from cistrack.fitting.fit_record_check import UTC_TOLERANCE_S

    recorded = units.parse_utc(record["scenario_epoch_utc"])  # checked by read_fit_record
    if abs((scen.epoch - recorded).total_seconds()) > UTC_TOLERANCE_S:
        raise ConfigError(f"{Path(d) / 'scenario.toml'}: epoch {units.format_utc(scen.epoch)} is not "
                          f"the scenario epoch {record['scenario_epoch_utc']} of {Path(d) / 'fit.json'} "
                          "(scenario_epoch_utc), which the fit's times count from: the folder was edited after the "
                          "fit; fit the observations again")


@dataclass(frozen=True)
class FitExportOptions:
    """How :func:`export_fit` exports a fitted orbit; each field is also one of its keywords.

    Attributes
    ----------
    overwrite : bool            replace an existing ``path``
    force : bool                export a fit that did not converge (the file says why in a COMMENT)
    predict_days : float|None   days of grid beyond the last observation, 0 to
                                :data:`MAX_PREDICT_DAYS` (0 when None)
    covariance : str            how the covariance is carried, one of
                                :data:`cistrack.least_squares.prediction.COVARIANCE_METHODS`
    """

    overwrite: bool = False
    force: bool = False
    predict_days: float | None = None
    covariance: str = "unscented"


def export_fit(run_dir: str | Path, format: str = "oem", path: str | Path | None = None, *,
               options: FitExportOptions | None = None, registry: Registry | None = None,
               words: ExportWords = PYTHON_EXPORT_WORDS, log: Callable[[str], None] | None = None,
               **params: Any) -> Path:
    """Write the fitted orbit of the fit directory ``run_dir`` with exporter ``format`` to ``path``
    (default ``RUN_DIR/estimate.<suffix>``, as for a run: one there holding a different export,
    e.g. without ``predict_days``, is refused unless ``overwrite``); returns the path.

    ``options`` (a :class:`FitExportOptions`), each field of which may also be given as a keyword
    (a keyword wins): ``overwrite``, ``force``, ``predict_days`` (>= 0, at most
    :data:`MAX_PREDICT_DAYS`) extends the grid beyond the last observation, ``covariance`` (one of
    :data:`cistrack.least_squares.prediction.COVARIANCE_METHODS`) says how the covariance is carried.
    The other keywords ``params`` go to the exporter. ``log`` is told, in a line each, where the
    predicted states end at an impact and when they go past the fit's horizon (both are also
    COMMENT WARNING lines of the file: :func:`prediction_warnings`). Refusals name the option as ``words`` say
    (Python's keywords; the command line passes its own): an existing ``path`` without
    ``overwrite``, a fit that did not converge without ``force``, an unknown ``covariance``."""
    opts, params = _split_keywords(options, params)
    days = _checked_request(opts, path, format, words)
    d = Path(run_dir)
    check_no_writer(d, "export")
    stamp = results_stamp(d)
    record = read_fit_record(d)
    refusal = _refusal(d, record, opts.force, words)
    reg = registry or default_registry()
    exporter = reg.create("exporter", format, **params)
    scen = _scenario(d, reg, record)
    frame = _inertial_frame(d, scen, reg)
    result = _result(record)
    arc = record["arc"]
    if format == "opm":
        times, n_arc = np.array([result.epoch]), 1
    else:
        times, n_arc = after_last_burn(record, *fit_grid(arc["first_tu"], arc["last_tu"], scen.epoch, days))
    _check_frame_years(d, frame, scen.epoch, result.epoch, times, days, words)
    dynamics = _dynamics(scen, reg, record)
    times, impact = prediction_end(dynamics, result, times, epoch=scen.epoch)  # an impact ends the file
    n_arc = min(n_arc, times.size)
    pred, held = _holding_line(_prediction(result, dynamics, times, opts.covariance), line_states(d, record),
                               dynamics, result.epoch, times)
    utc = np.array([units.format_utc(units.tu_to_utc(scen.epoch, float(t))) for t in times])
    refuse_non_finite(np.concatenate([pred.states, pred.covariances.reshape(times.size, -1)], axis=1), utc,
                      f"{d}: the states and covariances to export")
    ie = to_inertial(_estimates(times, n_arc, utc, pred), frame)
    name = str(record.get("designation") or scen.name)
    comments = _warnings(record, refusal, held) + _comments(record, name, opts, pred, utc, n_arc,
                                                            propagated=format != "opm")
    warned = prediction_warnings(record, times, n_arc, impact, scen.epoch)
    comments += [f"WARNING: {w}" for w in warned]
    if impact is not None:
        comments += ["WARNING: the orbit ends on the surface; the last state is 1 ms before the impact:"] + impact.lines()
    for w in warned if log is not None else ():
        log(f"note: {w}")
    out = Path(path) if path is not None else d / f"estimate{exporter.suffix}"
    meta = _metadata(name, comments, format != "opm")
    meta.update(_area_to_mass_user_defined(record))
    check_still_as_read(d, stamp, "export")  # a fit or run may have started (and ended) since it was read
    write_export(exporter, out, ie, meta, format=format, named=path is not None, overwrite=opts.overwrite,
                 words=words)
    return out


def _check_frame_years(d: Path, frame: Any, epoch: Any, fit_epoch: float, times: np.ndarray, days: float,
                       words: ExportWords) -> None:
    """Refuse (:class:`ConfigError`) states to export at ``times`` (TU since ``epoch``) outside the
    years its inertial ``frame`` holds for (``frame.years``: the real Earth-Moon frame's are DE421's),
    naming what put them there: fit.json's epoch_utc (the fit's epoch ``fit_epoch``), the
    prediction span (``days``, ``words.predict``), or fit.json's arc."""
    if frame.years is None:
        return
    first, last = frame.years
    ends = (float(times.min()), float(times.max())) if times.size else ()
    at = {t: units.tu_to_utc(epoch, t) for t in (float(fit_epoch), *ends)}
    bad = next((t for t in at if not first <= at[t].year <= last), None)
    if bad is None:
        return
    need = (f"its states in {frame.name} need the ephemeris of that frame ({frame.description}), which covers the "
            f"years {first} to {last}")
    again = "the directory does not hold an orbit cistrack can export: fit the observations again"
    if bad == fit_epoch:
        raise ConfigError(f"{d}: the orbit's epoch (fit.json epoch_utc) {at[bad]:%Y-%m-%d}: {need}; {again}")
    if days > 0 and bad == ends[1]:
        raise ConfigError(f"{words.option('predict', f'{days:g}')}: the states to export reach {at[bad]:%Y-%m-%d}: "
                          f"{need}; give a shorter {words.predict}")
    raise ConfigError(f"{d}: the fit's arc (fit.json arc) reaches {at[bad]:%Y-%m-%d}: {need}; {again}")


def prediction_warnings(record: dict[str, Any], times: np.ndarray, n_arc: int, impact: Any,
                        epoch: Any) -> list[str]:
    """What a reader of the predicted states (``times`` (K,) TU past the first ``n_arc``) must be
    told: that they end at an ``impact`` before the span asked, and that they run past the fit's
    horizon (``record["determination"]["horizon_days"]``), where the orbits the fit allows leave a
    1-degree field and the covariance may no longer hold the object, or past its covariance
    horizon (``covariance_horizon_days``, when sooner), where the covariance understates their spread,
    or, when the fit found neither, past the days it checked (:func:`checked_horizon_days`); and that
    they run farther before the first observation than that horizon (a prediction 140 days back had
    carried no word)."""
    if times.size <= n_arc:
        return []
    out = []
    if impact is not None:
        out.append(f"the predicted states end at the {impact.body}'s surface ({impact.kind} at "
                   f"{units.format_utc(units.tu_to_utc(epoch, impact.t_tu))[:19]}Z), before the span asked")
    last = float(record["arc"]["last_tu"])
    horizon = (record.get("determination") or {}).get("horizon_days")
    span = float(units.tu_to_days(float(times[-1]) - last))
    if isinstance(horizon, (int, float)) and math.isfinite(horizon) and span > horizon:
        when = units.format_utc(units.tu_to_utc(epoch, last + float(units.days_to_tu(horizon))))[:19]
        out.append(f"the predicted states run {span:.3g} days past the last observation, beyond the fit's horizon of "
                   f"{horizon:g} days ({when}Z): after it the orbits the fit allows leave a 1-degree field, and its "
                   "covariance may no longer hold the object; observe again before then")
    held = (record.get("determination") or {}).get("covariance_horizon_days")
    out += _backward_warning(record, times[n_arc:]) + _unchecked_warning(record, span)
    if isinstance(held, (int, float)) and math.isfinite(held) and span > held and not (
            isinstance(horizon, (int, float)) and held >= horizon):
        when = units.format_utc(units.tu_to_utc(epoch, last + float(units.days_to_tu(held))))[:19]
        out.append(f"the covariances understate the spread of the orbits the fit allows from {held:g} days past the "
                   f"last observation ({when}Z): more than 2 % of them lie outside the 99 % ellipsoid after it "
                   "(the flow bends across the covariance); treat its probabilities as optimistic there")
    return out


def checked_horizon_days(record: dict[str, Any]) -> float:
    """Days from the fit's arc (after its last observation, before its first) over which its orbits
    and covariance were checked to hold: the sooner of its horizons (``determination``'s
    ``covariance_horizon_days`` and ``horizon_days``), else the
    :data:`~cistrack.fitting.determination.HORIZON_DAYS` they were checked to."""
    from cistrack.fitting.determination import HORIZON_DAYS

    det = record.get("determination") or {}
    finite = [float(x) for x in (det.get("covariance_horizon_days"), det.get("horizon_days"))
              if isinstance(x, (int, float)) and math.isfinite(x)]
    return min(finite) if finite else HORIZON_DAYS


def beyond_checked_horizon(record: dict[str, Any], times: np.ndarray) -> np.ndarray:
    """Per time of ``times`` (K,) TU, whether it lies farther from the fit's arc (after its last
    observation or before its first) than :func:`checked_horizon_days`: where the predictions'
    covariance may understate their spread (K,) bool."""
    t = np.asarray(times, dtype=float)
    arc = record.get("arc") or {}
    limit = float(units.days_to_tu(checked_horizon_days(record)))
    out = np.zeros(t.shape, dtype=bool)
    if isinstance(arc.get("last_tu"), (int, float)):
        out |= t - float(arc["last_tu"]) > limit
    if isinstance(arc.get("first_tu"), (int, float)):
        out |= float(arc["first_tu"]) - t > limit
    return out


def _unchecked_warning(record: dict[str, Any], span: float) -> list[str]:
    """The words for predicted states ``span`` days past the last observation when the fit found
    neither horizon within the :func:`checked_horizon_days` it checked, and they run past that."""
    det = record.get("determination") or {}
    if any(isinstance(x, (int, float)) and math.isfinite(x)
           for x in (det.get("covariance_horizon_days"), det.get("horizon_days"))):
        return []
    limit = checked_horizon_days(record)
    if not span > limit:
        return []
    return [f"the predicted states run {span:.3g} days past the last observation, farther than the {limit:g} days the "
            "fit's orbits and covariance were checked for: the covariance may understate their spread there"]


def _backward_warning(record: dict[str, Any], times: np.ndarray) -> list[str]:
    """The words for predicted ``times`` (TU) farther before the first observation than the fit's
    horizons reach forward (:func:`checked_horizon_days`): nothing was checked backward, and a
    prediction 140 days back had carried no word."""
    first = (record.get("arc") or {}).get("first_tu")
    if not isinstance(first, (int, float)) or times.size == 0:
        return []
    back = float(units.tu_to_days(float(first) - float(np.min(times))))
    limit = checked_horizon_days(record)
    if not back > limit:
        return []
    return [f"the predicted states run {back:.3g} days before the first observation, farther back than the {limit:g} "
            "days the fit's orbits and covariance were checked for forward: the covariance may understate their spread "
            "there"]


def _prediction(result: FitResult, dynamics, times: np.ndarray, covariance: str):
    """The fit at ``times``: :func:`predict_orbit`, and with an estimated area-to-mass ratio the
    covariances of the joint covariance of state and ratio
    (:func:`cistrack.least_squares.area_to_mass.joint_covariances`)."""
    joint = joint_covariances(dynamics, result, times, covariance)
    if joint is None:
        return predict_orbit(result, dynamics, times, covariance=covariance)
    pred = predict_orbit(result, dynamics, times, covariance="linear")  # its states; not its covariances
    return pred._replace(covariances=joint[0], linear=joint[1])


def line_states(d: Path, rec: dict[str, Any]) -> np.ndarray | None:
    """The states (M, 6) [LU, VU, synodic, at the fit epoch] of ``d``'s ``lov.csv`` within the
    reach of the lowest chi-square (:data:`REACH_DELTA_CHI2` times :func:`covariance_scale`) when
    fit.json says the line is not linear; None otherwise, or when the file is missing. A damaged one
    (not a regular file, unreadable, a cell that is not a finite number, a column missing, no point,
    or a state no orbit of the fit's has: beyond 3e6 km or 100 km/s) is ignored too, with a warning
    naming it and what is wrong: the covariance is then the linear one, with its own warning."""
    from cistrack.interfaces.reader import not_a_file

    lov = rec.get("line_of_variations")
    if not isinstance(lov, dict) or lov.get("linear", True) or not isinstance(lov.get("file"), str):
        return None
    path = Path(d) / Path(lov["file"]).name
    why = not_a_file(path)  # a pipe or a device is never opened
    if why == "no such file":
        return None
    try:
        if why is not None:
            raise ValueError(why)
        chi2, km = _line_points(path)
    except ValueError as exc:
        warnings.warn(f"{path}: {exc}; the line of variations is ignored (fit the observations again to draw it anew)",
                      stacklevel=2)
        return None
    keep = chi2 <= chi2.min() + REACH_DELTA_CHI2 * covariance_scale(rec)
    return units.state_from_km(km)[keep]


_LINE_COLUMNS = ("chi2", "x_km", "y_km", "z_km", "vx_kms", "vy_kms", "vz_kms")
"""The columns of lov.csv a prediction reads."""


def _line_points(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(chi-square (M,), states (M, 6) km and km/s) of the points of a lov.csv; ValueError saying
    what is wrong when it cannot be read or holds what no fit writes."""
    from cistrack.fitting.fit_record_check import MAX_DISTANCE_KM, MAX_SPEED_KMS, within_reach

    try:
        with path.open(newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            missing = [c for c in _LINE_COLUMNS if c not in (reader.fieldnames or ())]
            if missing:
                raise ValueError(f"has no column {missing[0]!r} (a fit writes {', '.join(_LINE_COLUMNS)} and more)")
            rows = np.array([[_line_cell(r, c, n) for c in _LINE_COLUMNS] for n, r in enumerate(reader, 2)])
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"cannot be read ({exc})") from None
    if rows.size == 0:
        raise ValueError("holds no point of the line (its header only)")
    km = rows[:, 1:]
    if not np.all(within_reach(km)):
        raise ValueError(f"holds a state no orbit of the fit's has (beyond {MAX_DISTANCE_KM:.3g} km or "
                         f"{MAX_SPEED_KMS:g} km/s)")
    return rows[:, 0], km


def _line_cell(row: dict, column: str, line: int) -> float:
    """The finite number in ``column`` of a lov.csv ``row`` (on ``line``); ValueError naming both."""
    text = row.get(column)
    if text is None:
        raise ValueError(f"line {line} is short of column {column}")
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"line {line}, column {column}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"line {line}, column {column}: {text!r} is not a finite number")
    return value


def refuse_non_finite(values: np.ndarray, utc: Any, what: str) -> None:
    """Raise ConfigError naming ``what`` when ``values`` (K, ...), a row per time ``utc`` (K,), holds
    NaN or an infinity: no OEM or predictions CSV is written with one (a fit.json edited to a noise
    scale of 1e300 had given both, with exit status 0)."""
    if len(utc) == 0:
        return
    bad = ~np.all(np.isfinite(np.asarray(values, dtype=float).reshape(len(utc), -1)), axis=1)
    if np.any(bad):
        raise ConfigError(f"{what}: {int(np.sum(bad))} of {len(utc)} times hold a value that is not a finite number "
                          f"(NaN or infinite), the first at {str(utc[int(np.argmax(bad))])[:19]}Z; nothing was written: "
                          "the orbit it starts from (a fit.json, or a run's last estimate) is not one cistrack writes; "
                          "write that folder again ('cistrack fit' or 'cistrack run' into it with --overwrite)")


def line_drawn_short(rec: dict[str, Any]) -> str:
    """``, as far as it was drawn (...)`` when fit.json's line of variations ends inside its 3-sigma
    reach (``reach.open``: the orbits the data allow go on beyond its drawn end, e.g. a short
    ``fit.lov = N``), so that what holds "every orbit along the line" says it holds the drawn part
    only; "" otherwise."""
    lov = rec.get("line_of_variations")
    reach = lov.get("reach") if isinstance(lov, dict) else None
    if not isinstance(reach, dict) or not reach.get("open"):
        return ""
    return (", as far as it was drawn: the orbits the data allow go on beyond its end (draw it further with "
            "fit.lov = \"auto\" or a larger number of sigmas)")


def _holding_line(pred, line: np.ndarray | None, dynamics, t0: float, times: np.ndarray):
    """(``pred`` with each covariance widened to hold the orbits ``line`` (M, 6) at ``t0`` TU within
    3 sigma at its time (:func:`widened_to_hold`), True), or (``pred``, False) when there is no line
    or none of its orbits can be carried over the times (those that hit a body are left out)."""
    if line is None:
        return pred, False
    try:
        states, alive = ensemble_arc_states(dynamics, line, t0, times)   # (K, M, 6), (M,)
    except (PropagationError, StateError):
        return pred, False
    if not np.any(alive):
        return pred, False
    offsets = states[:, alive] - np.asarray(pred.states)[:, None, :]
    try:
        return pred._replace(covariances=np.array([widened_to_hold(c, o) for c, o in zip(pred.covariances, offsets)])), True
    except np.linalg.LinAlgError:  # a covariance the offsets make singular: the linear one, with its warning
        return pred, False


def _estimated_area_to_mass(record: dict[str, Any]) -> dict[str, Any] | None:
    """``fit.json``'s ``area_to_mass`` when the fit estimated it, else None."""
    amr = record.get("area_to_mass")
    return amr if isinstance(amr, dict) and amr.get("estimated") else None


def _dynamics(scen, reg: Registry, record: dict[str, Any]):
    """The scenario's dynamics, with the C_R A/m the fit estimated when it estimated one."""
    dyn = scen.build("dynamics", reg)
    amr = _estimated_area_to_mass(record)
    return dyn if amr is None else dyn.with_parameters(area_to_mass_m2_kg=float(amr["value_m2_kg"]))


def _area_to_mass_comments(record: dict[str, Any]) -> list[str]:
    """COMMENT lines on the estimated C_R A/m (none when it was not estimated)."""
    amr = _estimated_area_to_mass(record)
    if amr is None:
        return []
    corr = ", ".join(f"{c:.3f}" for c in amr["correlations_with_state"])
    return [f"solar radiation pressure C_R A/m estimated with the orbit: {amr['value_m2_kg']:.6g} +- "
            f"{amr['sigma_scaled_m2_kg']:.3g} m^2/kg (1 sigma, times the noise scale when above 1); its "
            f"correlations with X, Y, Z, X_DOT, Y_DOT, Z_DOT at the fit epoch (synodic): {corr}",
            "states predicted with that C_R A/m; the covariance is carried from the joint covariance of "
            "state and ratio (sigma points of both, each orbit with its own ratio), so it holds the ratio's "
            "uncertainty at every epoch"]


def _area_to_mass_user_defined(record: dict[str, Any]) -> dict[str, Any]:
    """``user_defined`` metadata (an exporter that writes USER_DEFINED_ keywords may use it):
    the estimated C_R A/m and its sigma, m^2/kg; empty when not estimated."""
    amr = _estimated_area_to_mass(record)
    if amr is None:
        return {}
    return {"user_defined": {"AREA_TO_MASS_M2_KG": float(amr["value_m2_kg"]),
                             "AREA_TO_MASS_SIGMA_M2_KG": float(amr["sigma_scaled_m2_kg"])}}


def _split_keywords(options: FitExportOptions | None, params: dict[str, Any]
                    ) -> tuple[FitExportOptions, dict[str, Any]]:
    """(``options`` with the keywords that name its fields replaced, the other keywords)."""
    names = {f.name for f in dataclasses.fields(FitExportOptions)}
    mine = {k: v for k, v in params.items() if k in names}
    rest = {k: v for k, v in params.items() if k not in names}
    return dataclasses.replace(options or FitExportOptions(), **mine), rest


def _checked_request(opts: FitExportOptions, path: str | Path | None, format: str, words: ExportWords) -> float:
    """The prediction span, days (0 when ``predict_days`` is None), once the covariance method,
    the output path and the span are valid (none for ``format`` opm, the one state at the fit
    epoch); raises ConfigError naming the option as ``words`` say."""
    w = words
    if format == "opm" and opts.predict_days is not None:
        raise ConfigError(f"{w.option('predict', opts.predict_days)}: {w.option('format', 'opm')} writes the one "
                          f"state at the fit epoch and takes no {w.predict}; {w.predict} extends the grid of "
                          f"{w.option('format', 'oem')} beyond the last observation")
    if opts.covariance not in COVARIANCE_METHODS:
        raise ConfigError(f"{w.covariance}{'' if w.covariance.endswith('=') else ' '}{opts.covariance!r}: must be "
                          f"one of {', '.join(COVARIANCE_METHODS)}")
    if path is not None and not opts.overwrite and os.path.lexists(path):
        raise ConfigError(f"{w.option('path', str(path))}: already exists; give another file, or {w.overwrite} to "
                          "replace it")
    days = 0.0 if opts.predict_days is None else opts.predict_days
    if not (isinstance(days, (int, float)) and math.isfinite(days) and 0.0 <= days <= MAX_PREDICT_DAYS):
        raise ConfigError(f"{w.predict}{'' if w.predict.endswith('=') else ' '}{opts.predict_days!r}: must be a "
                          f"number of days from 0 to {MAX_PREDICT_DAYS:g}")
    return days


def _refusal(d: Path, record: dict[str, Any], force: bool, words: ExportWords) -> str | None:
    """Why the fit should not be exported (None when it may be); raises CistrackError unless
    ``force``, and when there is no orbit at all."""
    refusal = fit_refusal(record)
    if "state" not in record:  # --force cannot help: there is no orbit to write
        raise CistrackError(f"{d}: nothing to export: {refusal}. See docs/real-data.md (when a fit fails)")
    if refusal is not None and not force:
        raise CistrackError(f"{d}: not exported: {refusal}. See docs/real-data.md (when a fit fails), or "
                            f"{words.force} to export it anyway (the file then says this in a COMMENT)")
    return refusal


def _inertial_frame(d: Path, scen, reg: Registry):
    """The inertial frame the scenario's sensor places its synodic frame in; raises CistrackError
    when it has none."""
    frame = scen.build("sensor", reg).inertial_frame()
    if frame is None:
        raise CistrackError(f"{d}: sensor '{scen.components['sensor'].name}' does not place its synodic frame in an "
                            "inertial frame; cannot export")
    return frame


def _estimates(times: np.ndarray, n_arc: int, utc: np.ndarray, pred) -> Estimates:
    """The predicted states (K, 6) and covariances (K, 6, 6) at ``times`` (K,) TU as one-component
    estimates in km and km/s, kind "fit" over the arc's first ``n_arc`` points and "predict" after."""
    states, covs = pred.states, pred.covariances
    k = len(times)
    kinds = np.array(["fit"] * n_arc + ["predict"] * (k - n_arc))
    return Estimates(step=np.arange(k), kind=kinds, t_tu=times, utc=utc, mean_km=states * KM_SCALE,
                     covariance_km=covs * np.multiply.outer(KM_SCALE, KM_SCALE), weights=[np.ones(1)] * k,
                     means_km=[(states[i] * KM_SCALE)[None] for i in range(k)],
                     covariances_km=[(covs[i] * np.multiply.outer(KM_SCALE, KM_SCALE))[None] for i in range(k)])


def _warnings(record: dict[str, Any], refusal: str | None, held: bool) -> list[str]:
    """The file's first COMMENT lines: when forced, why the fit is not a converged orbit; whether
    the covariances were widened to hold a line of variations that bends (``held``) or understate it."""
    out = [] if refusal is None else [
        f"WARNING: exported with --force although the fit is not a converged orbit: {refusal}"]
    doubt = covariance_doubt(record)
    if held:
        out.append("WARNING: the fit's line of variations bends away from the linear covariance (a poorly "
                   "determined orbit; fit.json, lov.csv): each covariance here is widened to hold every "
                   "orbit along the line within 3 sigma" + line_drawn_short(record))
    elif doubt is not None:
        out.append("WARNING: the fit's line of variations " + ("bends away from this covariance" if doubt == "bends"
                   else "could not be followed") + ": the covariance understates the uncertainty (a poorly "
                   "determined orbit; fit.json, lov.csv)")
    return out


def _comments(record: dict[str, Any], name: str, opts: FitExportOptions, pred, utc: np.ndarray, n_arc: int,
              propagated: bool = True) -> list[str]:
    """The file's COMMENT lines after :func:`_warnings`: the arc and fit, the covariance's scale and
    propagation (none when not ``propagated``: the one state at the fit epoch), the prediction span."""
    arc = record["arc"]
    comments = [f"least-squares orbit of {name} from {arc['n_observations']} observations "
                f"({arc['first_utc'][:19]}Z to {arc['last_utc'][:19]}Z, sites {', '.join(arc['sites'])}): "
                f"weighted RMS {record['rms']:.4g}, noise scale {noise_scale_text(record['noise_scale'])}, "
                f"{record['n_rejected']} rejected; fit epoch {record['epoch_utc'][:19]}Z"]
    comments += _covariance_comments(record, opts.covariance if propagated else None, pred.linear, utc)
    comments += _area_to_mass_comments(record)[:None if propagated else 1]  # at the epoch: nothing carried
    comments += _burn_comments(record, utc) if propagated else []
    if len(utc) > n_arc:
        days = 0.0 if opts.predict_days is None else opts.predict_days
        comments.append(f"states after {arc['last_utc'][:19]}Z are predicted beyond the last observation (made at "
                        f"that time): the grid runs {days:g} days past {utc[n_arc - 1][:19]}Z, its first state at or "
                        f"after that observation, in whole {GRID_MINUTES:g}-minute steps, to {utc[-1][:19]}Z")
    return comments


def _burn_comments(record: dict[str, Any], utc: np.ndarray) -> list[str]:
    """Where the states of a fit with burns start (:func:`after_last_burn`), and why; none without burns."""
    burns, last = _burns(record)
    if not burns or not len(utc):
        return []
    return [f"the fit found {len(burns)} impulsive burn(s) (fit.json maneuvers); the states start at "
            f"{utc[0][:19]}Z, {BURN_MARGIN_SIGMAS:g} sigma after the last ({str(last.get('t_burn_utc', '?'))[:19]}Z "
            f"+- {24.0 * float(last.get('t_burn_sigma_days') or 0.0):.2g} h, {float(last['delta_v_ms']):.3g} m/s) or "
            "at the fit epoch: before it the object flew another orbit"]


def _covariance_comments(record: dict[str, Any], covariance: str | None, linear: np.ndarray,
                         utc: np.ndarray) -> list[str]:
    """How the covariance was scaled and propagated (``covariance`` None: not propagated, the fit's
    own at its epoch); a warning naming the span of the ``linear`` (K,) bool points when the
    unscented transform fell back to transition matrices there."""
    comments = []
    if covariance_scale(record) > 1.0:
        comments.append(f"covariance scaled by the noise scale squared ({covariance_scale(record):.4g}): the "
                        "post-fit residuals exceed the stated noise")
    if covariance is None:
        comments.append("covariance of the fit at its epoch, not propagated")
        return comments
    if covariance == "linear":
        comments.append("covariance propagated linearly (state transition matrices)")
        return comments
    points = "14 sigma points of state and C_R A/m" if _estimated_area_to_mass(record) else "12 sigma points"
    comments.append(f"covariance propagated by the unscented transform (the fit state and {points} "
                    "through the dynamics)")
    if np.any(linear):
        where = np.flatnonzero(linear)
        comments.append(f"WARNING: {where.size} of {len(utc)} covariances, between {utc[where[0]][:19]}Z and "
                        f"{utc[where[-1]][:19]}Z, are propagated linearly: a sigma-point orbit hit a body or "
                        "could not be propagated, or the fit covariance is not positive semi-definite")
    return comments


def _metadata(name: str, comments: list[str], grid: bool = True) -> dict[str, Any]:
    """The exporter's ``meta``: names, COMMENT lines and what the states are (``grid``: propagated
    over the grid; else the one state at the fit epoch)."""
    what = (f"least-squares state and covariance propagated every {GRID_MINUTES:g} min, km and km/s" if grid else
            "least-squares state and covariance at the fit epoch, km and km/s")
    return {"object_name": name, "object_id": name, "originator": "cistrack", "comments": comments,
            "interpolation": "LAGRANGE", "interpolation_degree": INTERPOLATION_DEGREE, "data_comment": what}
