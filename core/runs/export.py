"""Exporting a run's orbit estimate: ``cistrack export RUN --format oem|opm`` and
:func:`export_run`.

The run directory holds ``estimates.parquet`` (synodic, km) and the scenario as run; the
scenario's sensor places the synodic frame in inertial space
(:meth:`cistrack.interfaces.Sensor.inertial_frame`), the estimates are carried there with the
exact Jacobian of that map, and the registered exporter writes the file.
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from cistrack.errors import CistrackError, ConfigError
from cistrack.results.estimates import read_estimates
from cistrack.results.inertial_frame import InertialEstimates, to_inertial
from cistrack.plugin.registry import Registry, default_registry

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["export_run", "run_inertial_estimates"]


def _scenario_of(run_dir: Path, reg: Registry):
    from cistrack.scenario.loading import parse_scenario
    toml_path, json_path = run_dir / "scenario.toml", run_dir / "scenario.json"
    if toml_path.exists():
        raw = tomllib.loads(toml_path.read_text())
    elif json_path.exists():
        raw = json.loads(json_path.read_text())
    else:
        raise ConfigError(f"{run_dir}: not a cistrack run directory (no scenario.toml); run "
                          f"'cistrack run ... --out DIR' first")
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
        est = read_estimates(d)
    except FileNotFoundError as exc:
        raise CistrackError(str(exc)) from None
    return to_inertial(est, frame), scen


def export_run(run_dir: str | Path, format: str = "oem", path: str | Path | None = None,
               registry: Registry | None = None, overwrite: bool = False, **params: Any) -> Path:
    """Write the estimate of the run in ``run_dir`` with exporter ``format`` ("oem", "opm", ...)
    to ``path`` (default ``RUN_DIR/estimate.<format>``, the run's own file, replaced on each
    export); returns the path written. An existing ``path`` is refused (before anything is
    read) unless ``overwrite``."""
    if path is not None and not overwrite and os.path.lexists(path):
        raise ConfigError(f"--out {path}: already exists; give another file, or add --overwrite to "
                          f"replace it")
    reg = registry or default_registry()
    exporter = reg.create("exporter", format, **params)
    ie, scen = run_inertial_estimates(run_dir, reg)
    out = Path(path) if path is not None else Path(run_dir) / f"estimate{exporter.suffix}"
    manifest = Path(run_dir) / "manifest.json"
    run_id = json.loads(manifest.read_text()).get("run_id", scen.name) if manifest.exists() else scen.name
    exporter.write(out, ie, {"object_name": scen.name, "object_id": run_id, "originator": "cistrack"})
    return out
