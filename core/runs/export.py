"""Exporting a run's orbit estimate: ``cistrack export RUN --format oem|opm`` and
:func:`export_run`.

The run directory holds ``estimates.parquet`` (synodic, km) and the scenario as run; the
scenario's sensor places the synodic frame in inertial space
(:meth:`cistrack.interfaces.Sensor.inertial_frame`), the estimates are carried there with the
exact Jacobian of that map, and the registered exporter writes the file (through a temporary file
and a rename: a full disk never leaves a partial file that would block the next export).

Only a run that finished and did not diverge is exported (:func:`export_refusal` says why not):
the estimate of a failed, killed or still-running run stops wherever the run stopped, and that
of a diverged filter is not an orbit. ``force`` exports such a run anyway, and the file then says
so in a COMMENT line (exporters read ``meta["comments"]``).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable

from cistrack.errors import CistrackError, ConfigError
from cistrack.results.export_file import PYTHON_EXPORT_WORDS, ExportWords, write_export
from cistrack.results.dir_lock import check_no_writer, check_unchanged, results_stamp
from cistrack.results.estimates import usable_estimates
from cistrack.results.run_status import run_status
from cistrack.results.inertial_frame import InertialEstimates, to_inertial
from cistrack.plugin.registry import Registry, default_registry

__all__ = ["export_run", "export_refusal", "run_inertial_estimates", "scenario_of"]

FIT_SOURCE = "cistrack fit"
"""How the manifest of the filter run inside a ``cistrack fit`` directory starts its ``scenario_source``."""


def scenario_of(run_dir: str | Path, reg: Registry | None = None):
    """The scenario a run or fit directory ran (its ``scenario.toml``, or ``scenario.json``),
    parsed; ConfigError when the directory has neither."""
    return _scenario_of(Path(run_dir), reg or default_registry())


def _fit_begun(d: Path) -> str:
    """What ``d`` is when it holds a fit's start marker but no scenario (a fit stopped before its
    filter run began), in words; "" otherwise."""
    from cistrack.results.output_paths import FIT_STARTED

    if not (Path(d) / FIT_STARTED).is_file():
        return ""
    return (f"{d}: a 'cistrack fit' began here and stopped before its filter run started (no scenario.toml): "
            "there is no orbit yet; run 'cistrack fit' into it again")


def _not_a_run(d: Path, advice: str) -> str:
    """Why ``d`` is not a run directory (no scenario), ending with ``advice``; when it holds fits one
    folder each (several objects: ``fit-*``; ``fit.arcs=each``: ``arc-*``) it names them instead."""
    from cistrack.results.output_paths import fit_folders_inside

    for pattern, what in (("arc-*", "one fit per arc (fit.arcs=each)"), ("fit-*", "the fits of several objects")):
        fits = fit_folders_inside(d, pattern) if d.is_dir() else []
        if fits:
            shown = ", ".join(fits[:4]) + (f" and {len(fits) - 4} more" if len(fits) > 4 else "")
            return (f"{d}: holds {what}, one folder each ({shown}), not one orbit: give one of them, "
                    f"e.g. {d / fits[-1]}")
    return _fit_begun(d) or f"{d}: not a cistrack run directory (" + (
        "no scenario.toml" if d.is_dir() else "no such directory") + f"); {advice}"


def _scenario_of(run_dir: Path, reg: Registry):
    from cistrack.scenario.loading import parse_scenario, recorded_scenario
    toml_path, json_path = run_dir / "scenario.toml", run_dir / "scenario.json"
    if os.path.lexists(toml_path):
        return recorded_scenario(toml_path, reg)
    if json_path.exists():
        raw = json.loads(json_path.read_text())
    else:
        raise ConfigError(_not_a_run(run_dir, "run 'cistrack run ... --out DIR' first"))
    return parse_scenario(raw, str(toml_path), reg)


def run_inertial_estimates(run_dir: str | Path, registry: Registry | None = None) -> tuple[InertialEstimates, Any]:
    """The run's per-step estimates in its sensor's inertial frame, and the scenario."""
    d = Path(run_dir)
    reg = registry or default_registry()
    scen = _scenario_of(d, reg)
    sensor = scen.build("sensor", reg)
    frame = sensor.inertial_frame()
    if frame is None:
        raise CistrackError(f"{d}: sensor '{scen.components['sensor'].name}' does not place its synodic frame "
                            f"in an inertial frame (Sensor.inertial_frame() is None); cannot export")
    try:
        est = usable_estimates(d)
        return to_inertial(est, frame), scen
    except FileNotFoundError as exc:
        raise CistrackError(str(exc)) from None
    except CistrackError:
        raise
    except (ValueError, TypeError, IndexError) as exc:  # a table that reads but holds what no run writes
        raise CistrackError(f"{d}: its estimates are damaged ({str(exc)[:120]}); run the scenario again into "
                            f"{d} with --overwrite") from None


def export_refusal(run_dir: str | Path) -> str | None:
    """Why the estimate of the run in ``run_dir`` should not be exported without ``force``: it
    did not finish (failed, filter-failed, interrupted or killed, still running, or no readable
    manifest tells), its filter diverged, or it is the filter run of a fit whose ``fit.json`` was
    never written (the fit failed to write its results); None for a finished run that did not diverge."""
    d = Path(run_dir)
    if not (d / "manifest.json").is_file():
        return "it has no manifest.json, so whether it finished is unknown"
    try:
        status, reason = run_status(d)
        man = json.loads((d / "manifest.json").read_text())
    except (OSError, ValueError) as exc:
        return f"its manifest.json cannot be read ({exc}), so whether it finished is unknown"
    why = f" ({reason})" if reason else ""
    if str(man.get("scenario_source", "")).startswith(FIT_SOURCE) and not (d / "fit.json").is_file():
        return ("it is the filter run of a 'cistrack fit' whose fit did not complete (no fit.json): its estimate "
                "is not the fitted orbit; run 'cistrack fit' into it again")
    if status == "running":
        proc = man.get("process") or {}
        return (f"it is still running (process {proc.get('pid', '?')} on {proc.get('host', '?')}); its "
                f"estimate stops at the last step written")
    if status == "interrupted":
        return f"it was interrupted or killed before it finished{why}; its estimate stops where it stopped"
    if status != "finished":
        return f"it did not finish (status '{status}'{why}); its estimate stops where the run stopped"
    return _verdict_refusal(man.get("summary"))


def _verdict_refusal(summary: Any) -> str | None:
    """Why a finished run's manifest ``summary`` is not exported: it is missing or damaged (the
    reading :func:`cistrack.read_run` refuses too), or its filter diverged; None otherwise."""
    from cistrack.evaluation.run_summary import RunSummary

    if summary is None:
        return "its manifest.json holds no run summary, so the run's verdict is unknown"
    if not isinstance(summary, dict) or ("verdict" in summary and not isinstance(summary["verdict"], dict)):
        return "its manifest.json's summary or verdict is not a table, so the run's verdict is unknown"
    try:
        verdict = RunSummary.from_dict(summary).verdict
    except ValueError as exc:
        return f"its manifest.json's summary is not one a run writes ({exc}), so the run's verdict is unknown"
    if verdict.kind == "diverged":
        return "its filter diverged" + (f" ({verdict.reason})" if verdict.reason else "") + \
            "; the estimate is not a usable orbit"
    return None


def export_run(run_dir: str | Path, format: str = "oem", path: str | Path | None = None,
               registry: Registry | None = None, overwrite: bool = False, force: bool = False,
               log: Callable[[str], None] | None = None, words: ExportWords = PYTHON_EXPORT_WORDS,
               **params: Any) -> Path:
    """Write the estimate of the run in ``run_dir`` with exporter ``format`` ("oem", "opm", ...)
    to ``path`` (default ``RUN_DIR/estimate.<format>``, the run's own file: written again with the
    same content by the same export, but an export with other options there is refused unless
    ``overwrite``, :func:`cistrack.results.export_file.write_export`); returns the path written.
    ``words``: how refusals name the options (``path=``, ``overwrite=True`` from Python; the command
    line passes :data:`cistrack.results.export_file.CLI_EXPORT_WORDS`).
    An existing ``path`` is refused (before anything is read) unless ``overwrite``; a run that did not finish or diverged (:func:`export_refusal`)
    unless ``force``, and then the file carries the reason as a COMMENT. ``log`` receives a line
    per stage (:func:`cistrack.runs.progress.stage_log`)."""
    if path is not None and not overwrite and os.path.lexists(path):
        raise ConfigError(f"{words.option('path', str(path))}: already exists; give another file, or "
                          f"{words.overwrite} to replace it")
    if path is not None and not Path(path).parent.is_dir():  # said before a word of "writing ..." (probe I8)
        raise ConfigError(f"{words.option('path', str(path))}: the folder {Path(path).parent} does not exist; give a "
                          "file in an existing folder")
    d = Path(run_dir)
    if not d.is_dir() or not ((d / "scenario.toml").is_file() or (d / "scenario.json").is_file()):
        raise ConfigError(_not_a_run(d, "give the --out directory of a 'cistrack run'"))
    _check_not_being_replaced(d)
    stamp = results_stamp(d)
    refusal = export_refusal(d)
    if refusal is not None and not force:
        raise CistrackError(f"{d}: not exported: {refusal}. Export only finished runs, or {words.force} to "
                            f"export it anyway (the file then says this in a COMMENT)")
    reg = registry or default_registry()
    exporter = reg.create("exporter", format, **params)
    say = log or (lambda m: None)
    say(f"reading the estimates of {d} and carrying them into the sensor's inertial frame")
    ie, scen = run_inertial_estimates(d, reg)
    out = Path(path) if path is not None else d / f"estimate{exporter.suffix}"
    what = _what_is_written(exporter, ie)
    if what is not None:  # a step the run lacks: the exporter refuses it, naming the steps there are
        say(f"writing {what} as {format} to {out}")
    manifest = d / "manifest.json"
    try:
        run_id = json.loads(manifest.read_text()).get("run_id", scen.name) if manifest.exists() else scen.name
    except (OSError, ValueError):
        run_id = scen.name
    meta = {"object_name": scen.name, "object_id": run_id, "originator": "cistrack"}
    if refusal is not None:
        meta["comments"] = [f"WARNING: exported with --force although run {run_id} is not a finished, "
                            f"converged run: {refusal}"]
    check_no_writer(d, "export", runs=False)  # a fit may have started in the directory since it was read
    if not force:  # a forced export of a running run reads a manifest that changes as it runs
        check_unchanged(d, stamp, "export")
    write_export(exporter, out, ie, meta, format=format, named=path is not None, overwrite=overwrite, words=words)
    return out


def _check_not_being_replaced(d: Path) -> None:
    """Refuse while a fit holds ``d``'s lock, or a run does while the manifest is not that run's
    ("running"): a ``cistrack run --overwrite`` replacing a finished run holds the lock before it
    writes its manifest, and the export would have written the orbit being replaced. A running
    run's own estimate is refused by :func:`export_refusal` unless ``force``."""
    check_no_writer(d, "export", runs=False)
    try:
        check_no_writer(d, "export")
    except CistrackError:
        try:
            running = run_status(d)[0] == "running"
        except (OSError, ValueError, CistrackError):
            running = False
        if not running:
            raise


def _what_is_written(exporter: Any, ie: InertialEstimates) -> str | None:
    """``15 estimates``, or for an exporter of one step (its ``step`` parameter, -1 the last)
    ``step 3``; None for a step the run does not have."""
    step = getattr(exporter, "step", None)
    if isinstance(step, int) and not isinstance(step, bool) and len(ie.step):
        if step != -1 and step not in {int(s) for s in ie.step}:
            return None
        return f"step {int(ie.step[-1]) if step == -1 else step}"
    return f"{len(ie.t_tu)} estimates"
