"""Results of a run on disk, written as the run goes.

Layout of a run directory::

    manifest.json        scenario, seed, versions, timings, status ("running", "finished",
                         "filter-failed", "failed" or "interrupted", with the reason in
                         summary.failure), the running process (host, pid: a "running" run
                         whose process is gone reads as interrupted, see cistrack.results.run_status)
    scenario.toml        the scenario as run (tables after overrides, with the seed run)
    steps.parquet        one row per step (written when the run finishes)
    steps/part-*.parquet the rows while running, many steps per part (see
                         :mod:`cistrack.results.part_files`: a part per ``rows_per_part`` steps or per
                         ``seconds_per_part`` of wall time, atomic rename, so a killed run
                         leaves every written part readable); merged into steps.parquet at the end

:func:`read_steps` reads either form.
"""
from __future__ import annotations

import json
import os
import platform
import socket
import time
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from cistrack.errors import CistrackError
from cistrack.interrupts import interrupt_text
from cistrack.results.atomic_files import atomic_target, write_text_atomic
from cistrack.results.strict_json import finite_or_null
from cistrack.results.fingerprint import scenario_fingerprint, tables_as_run
from cistrack.plugin.hookspecs import hookimpl
from cistrack.results.output_paths import clear_earlier_results
from cistrack.results.part_files import ROWS_PER_PART, SECONDS_PER_PART, PartWriter, read_checked, read_parts, write_checked
from cistrack.results.step_table import is_table_step, row_of

__all__ = ["ResultsWriter", "read_steps", "steps_readable", "read_manifest", "results_line", "write_json_atomic", "versions"]

MANIFEST = "manifest.json"
STEPS = "steps.parquet"
PARTS = "steps"
RESIDUALS_FIGURE = "residuals.svg"
"""A filter run's residual figure (:mod:`cistrack.runs.residual_figure`)."""


def write_json_atomic(path: Path, data: dict) -> None:
    """Write JSON to ``path`` via a temporary file and rename (never a half-written file; the
    temporary file is removed when writing fails, e.g. on a full disk). Strict JSON: a NaN or
    infinite number is written as null (:func:`~cistrack.results.strict_json.finite_or_null`)."""
    write_text_atomic(path, json.dumps(finite_or_null(data), indent=2, sort_keys=True, default=_json_default,
                                       allow_nan=False))


def _json_default(o: Any):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def versions(registry=None) -> dict[str, str]:
    """Versions of python, numpy, cistrack and every distribution that provides a plugin."""
    out = {"python": platform.python_version(), "numpy": np.__version__}
    try:
        out["cistrack"] = metadata.version("cistrack")
    except metadata.PackageNotFoundError:
        out["cistrack"] = "unknown"
    if registry is not None:
        # once per distribution: every lookup scans sys.path (the built-ins are 27 entry points
        # of one distribution: 10 ms of each run)
        for dist in dict.fromkeys(d for d, _ep, _mod in registry.plugins):
            if dist in out:
                continue
            try:
                out[dist] = metadata.version(dist)
            except metadata.PackageNotFoundError:
                pass
    return out


def _json_safe(meta: dict) -> dict:
    """The entries of a meta dict that JSON can hold (str, numbers, bools, lists and dicts of them)."""
    def ok(v) -> bool:
        if isinstance(v, (str, int, float, bool)) or v is None:
            return True
        if isinstance(v, (list, tuple)):
            return all(ok(x) for x in v)
        if isinstance(v, dict):
            return all(isinstance(k, str) and ok(x) for k, x in v.items())
        return False
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in meta.items() if ok(v)}


class ResultsWriter:
    """Lifecycle observer that writes a run's manifest and per-step table into ``directory``;
    the rows go to part files of ``rows_per_part`` steps (or fewer, every ``seconds_per_part``
    seconds), see :class:`cistrack.results.part_files.PartWriter`."""

    def __init__(self, directory: str | Path, registry=None, rows_per_part: int = ROWS_PER_PART,
                 seconds_per_part: float = SECONDS_PER_PART) -> None:
        self.directory = Path(directory)
        self.registry = registry
        self._t0 = 0.0
        self._manifest: dict[str, Any] = {}
        self._parts = PartWriter(self.directory / PARTS, rows_per_part, seconds_per_part)

    @hookimpl
    def cistrack_run_started(self, run) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        self._parts.start()
        if (self.directory / STEPS).exists():
            (self.directory / STEPS).unlink()
        clear_earlier_results(self.directory)  # an earlier run's exports and fit files
        self._t0 = time.perf_counter()
        scen = run.scenario
        iod_meta = getattr(run.iod_cloud, "meta", None) or {}
        self._manifest = {
            "run_id": run.run_id, "scenario": scen.name, "scenario_source": scen.source,
            "seed": int(run.seed), "status": "running", "epoch": run.epoch.isoformat(),
            "fingerprint": scenario_fingerprint(scen, run.seed),
            "components": {t: {"name": s.name, "params": {k: (v.name if hasattr(v, "kind") and hasattr(v, "params") else v)
                                                         for k, v in s.params.items()}}
                           for t, s in scen.components.items()},
            "versions": versions(self.registry), "machine": {"platform": platform.platform(),
                                                             "processor": platform.processor(),
                                                             "cpu_count": os.cpu_count()},
            "n_measurements": len(run.measurements), "n_passes": len(run.passes),
            # what the measurements are and which corrections made them (e.g. real-telescope's
            # measurement kind, frame, site and applied corrections)
            "measurement_model": _json_safe(getattr(run.measurements, "meta", None) or {}),
            "iod": {"epoch_tu": float(run.iod_cloud.epoch), "n_particles": len(run.iod_cloud),
                    **{k: v for k, v in iod_meta.items() if isinstance(v, (int, float, str, bool))},
                    # first-pass gross outliers the IOD left out (plugins/iod/pass_screen.py), if any
                    **({"screened_out": [dict(x) for x in iod_meta["screened_out"]]}
                       if iod_meta.get("screened_out") else {})},
            "started_unix": time.time(),
            "process": {"host": socket.gethostname(), "pid": os.getpid()},  # see cistrack.results.run_status
        }
        # the manifest first: a folder a failed write left without it holds nothing a retry must keep
        write_json_atomic(self.directory / MANIFEST, self._manifest)
        _write_scenario(self.directory, tables_as_run(scen.raw, run.seed))

    @hookimpl
    def cistrack_step_updated(self, run, step) -> None:
        self._write_part(run, step)

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        if is_table_step("predicted", step):  # a prediction-only step is a row of its own
            self._write_part(run, step)

    def _write_part(self, run, step) -> None:
        self._parts.add(step.index, row_of(run, step))

    @property
    def n_parts(self) -> int:
        """Part files written so far in this run."""
        return self._parts.n_parts

    @hookimpl(trylast=True)  # after every other observer: it records their failures in the manifest
    def cistrack_run_finished(self, run, summary) -> None:
        """Write the waiting rows, merge the parts into steps.parquet and record the status. If
        writing fails (a full disk) the parts written stay (``read_steps`` reads them), the
        manifest says "failed" and why, and the error is raised again (after the manifest is
        written) so that the run's summary says so too. An interrupt (Ctrl-C, SIGTERM) while it
        merges leaves the parts too, and the manifest says "interrupted" before it is raised again."""
        status, extra, problems, interrupt = summary.status, {}, [], None
        if not self._manifest:  # the run failed before this observer saw it start (another observer's start)
            self.directory.mkdir(parents=True, exist_ok=True)
            self._manifest = {"run_id": run.run_id, "scenario": run.scenario.name, "seed": int(run.seed),
                              "versions": versions(self.registry), "started_unix": time.time()}
            self._t0 = time.perf_counter()
        try:
            self._merge_parts(extra, problems)
        except KeyboardInterrupt as exc:
            interrupt, status = exc, "interrupted"
            problems.append(f"{interrupt_text(exc)} while merging the steps into {STEPS}: they stay in {PARTS}/")
        data = summary.to_dict()
        if problems:
            status = "failed" if status == "finished" else status
            data["failure"] = "; ".join(([data["failure"]] if data.get("failure") else []) + problems)
        data["status"] = status
        self._manifest.update({"status": status, "summary": data, **extra,
                               "wall_time_s": time.perf_counter() - self._t0,
                               "finished_unix": time.time()})
        write_json_atomic(self.directory / MANIFEST, self._manifest)
        if interrupt is not None:
            raise interrupt
        if problems:
            raise OSError(f"{self.directory}: " + "; ".join(problems))

    def _merge_parts(self, extra: dict, problems: list[str]) -> None:
        """Write the waiting rows and merge the part files into steps.parquet; what fails (OSError)
        is added to ``extra`` (manifest key -> text) and ``problems``."""
        try:
            self._parts.flush()
        except OSError as exc:
            extra["part_failure"] = f"{type(exc).__name__}: {exc}; the last rows were not written"
            problems.append(f"writing the last steps to {PARTS}/: {extra['part_failure']}")
        parts = self._parts.parts()
        extra["n_parts"] = self._parts.n_parts
        if parts:
            try:
                table = read_parts(self.directory / PARTS)
                with atomic_target(self.directory / STEPS, STEPS + ".tmp") as tmp:
                    write_checked(table, tmp)
                for p in parts:
                    p.unlink()
            except OSError as exc:
                extra["merge_failure"] = (f"{type(exc).__name__}: {exc}; the completed steps stay in the "
                                          f"{len(parts)} files {PARTS}/part-*.parquet")
                problems.append(f"merging into {STEPS}: {extra['merge_failure']}")


STEP_KEYS = ("step", "t_days")
"""Columns of every step table (:func:`read_steps` refuses one without them)."""


def _write_scenario(directory: Path, tables: dict) -> None:
    """``scenario.toml`` of ``tables`` (``scenario.json`` when tomli_w is not installed or a value
    cannot be TOML), removing the other one an earlier run may have left."""
    try:
        import tomli_w  # optional: nicer record of the scenario as run
        name, text = "scenario.toml", tomli_w.dumps(tables)
    except Exception:  # not installed, or a value TOML cannot hold: JSON instead
        name, text = "scenario.json", json.dumps(tables, indent=2, default=str)
    write_text_atomic(directory / name, text)  # a failing write (full disk) is raised, never hidden
    stale = directory / ("scenario.json" if name == "scenario.toml" else "scenario.toml")
    if stale.is_file():
        stale.unlink()


def steps_readable(directory: str | Path) -> bool:
    """Whether the run in ``directory`` has a merged step table whose Parquet footer can be read (a
    truncated or overwritten file cannot): a cheap check, without reading the table."""
    try:
        pq.read_metadata(Path(directory) / STEPS)
    except (pa.ArrowException, OSError):
        return False
    return True


def read_manifest(directory: str | Path) -> dict:
    """The manifest of a run directory (a JSON object); ValueError naming the file when it holds
    something else (a list, a number)."""
    path = Path(directory) / MANIFEST
    man = json.loads(path.read_text())
    if not isinstance(man, dict):
        raise ValueError(f"{path}: not a cistrack manifest (a JSON {type(man).__name__}, not an object)")
    return man


def read_steps(directory: str | Path) -> pa.Table:
    """The per-step table of a run: steps.parquet, or the parts a killed run left behind.
    :class:`~cistrack.errors.CistrackError` naming the file when steps.parquet is not a Parquet table
    (truncated, or written over by something else)."""
    d = Path(directory)
    if (d / STEPS).exists():
        try:
            return _in_step_order(read_checked(d / STEPS), d / STEPS)
        except (pa.ArrowException, OSError) as exc:
            raise CistrackError(f"{d / STEPS}: not a readable step table ({exc}); run the scenario again into "
                                f"{d} (a study reruns it)") from None
    table = read_parts(d / PARTS)
    if table is None:
        raise FileNotFoundError(f"{d}: no results (neither {STEPS} nor {PARTS}/part-*.parquet)")
    return _in_step_order(table, d / PARTS)


def _in_step_order(table: pa.Table, where: Path) -> pa.Table:
    """``table``'s rows in step order; CistrackError naming ``where`` when it lacks a column every
    step table has (``step``, ``t_days``: an edited or foreign table)."""
    missing = [c for c in STEP_KEYS if c not in table.column_names]
    if missing:
        raise CistrackError(f"{where}: not a steps table (no column {', '.join(missing)}); run the scenario again "
                            f"into {where.parent} (a study reruns it)")
    return table.sort_by("step")


def _stale_note(path: Path) -> str:
    """For a manifest still saying "running" once the run is over (its final version could not be
    written, e.g. on a full disk): a note saying so; else nothing."""
    if path.name != MANIFEST:
        return ""
    try:
        status = json.loads(path.read_text()).get("status")
    except (OSError, ValueError, AttributeError):
        return " (unreadable)"
    return " (still says 'running': its final version could not be written)" if status == "running" else ""


def results_line(directory: str | Path) -> str:
    """The line naming a run's results for a person (``cistrack run``): only files that exist (the
    step table, the manifest, the residual figure), the unmerged parts of a run whose merge
    failed, or that nothing was written."""
    d = Path(directory)
    found = [f"{d}/{STEPS}"] if (d / STEPS).is_file() else []
    n_parts = len(list((d / PARTS).glob("part-*.parquet"))) if (d / PARTS).is_dir() else 0
    if not found and n_parts:
        found.append(f"{d}/{PARTS}/part-*.parquet ({n_parts} files, not merged)")
    found += [f"{d}/{name}" + _stale_note(d / name) for name in (MANIFEST, RESIDUALS_FIGURE) if (d / name).is_file()]
    if not found:
        return f"  results: none written in {d}"
    return "  results: " + ", ".join(found)
