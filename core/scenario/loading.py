"""Scenario files (TOML): validated before anything runs.

A scenario names each component by its registry name plus parameters::

    name = "example-1"
    description = "9:2 NRHO, uniform-range IOD, PGM, one orbit"
    epoch = "2026-01-01T00:00:00Z"     # UTC of t = 0
    seed = 1
    duration_days = 6.6

    [truth]
    orbit = "nrho-9-2"                  # a registered orbit, or state_km = [x, y, z, vx, vy, vz]

    [dynamics]
    name = "cr3bp"

    [sensor]
    name = "ground-telescope"
    measure_range = true

    [schedule]
    name = "paper-example-1"

    [iod]
    name = "uniform-range"

    [filter]
    name = "pgm"
    n_particles = 10000
    [filter.clusterer]                 # a parameter that is itself a component
    name = "kmeans"

Every error names the file, the table and the key, and what is allowed.
"""
from __future__ import annotations

import copy
import os
import sys
from dataclasses import dataclass, field
from datetime import date, datetime
from pathlib import Path
from typing import Any

import numpy as np

from cistrack import units
from cistrack.scenario.builtin_scenarios import builtin_scenario_path, builtin_scenarios
from cistrack.scenario.component_choice import choose_tables, keep_choice_table, recorded_tables
from cistrack.plugin.component_tables import ComponentSpec, check_keys, component_spec, example_name, typed
from cistrack.evaluation.custody import CustodyRule
from cistrack.scenario.custody_table import custody_rule
from cistrack.scenario.maneuver_table import ManeuverSettings, maneuver_settings
from cistrack.scenario.observer_tables import observer_specs
from cistrack.scenario.limits import check_memory, check_path_component, check_seed
from cistrack.scenario import toml_input
from cistrack.scenario.work_limits import check_epoch_span, check_steps
from cistrack.errors import ConfigError, UnknownComponentError, quoted
from cistrack.interfaces import ReferenceOrbit
from cistrack.plugin.registry import Registry, default_registry

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Scenario", "ComponentSpec", "CustodyRule", "load_scenario", "parse_scenario", "relative_base", "recorded_scenario",
           "builtin_scenarios", "builtin_scenario_path", "COMPONENT_TABLES"]

COMPONENT_TABLES: dict[str, str] = {
    "dynamics": "dynamics", "sensor": "sensor", "schedule": "schedule", "iod": "iod", "filter": "filter",
}
"""Scenario table -> registry kind of the component it builds."""

_TOP_KEYS = {"name", "description", "epoch", "seed", "duration_days", "truth", "custody", "run",
             "measurements", "sensors", "maneuvers", *COMPONENT_TABLES}
_REQUIRED_TABLES = ("dynamics", "iod", "filter")
_TRUTH_KEYS = {"orbit", "state_km", "dynamics", "maneuvers"}
_RUN_KEYS = {"truth_grid_minutes", "predict_every_hours", "end_with_prediction", "recording_frame",
             "iod_observer"}
_MEAS_KEYS = {"file", "reader"}


@dataclass
class Scenario:
    """A validated scenario. :meth:`build` hands out each component validation constructed, then
    fresh ones (see :class:`ComponentSpec`)."""

    name: str
    description: str
    epoch: datetime
    seed: int
    duration_days: float
    components: dict[str, ComponentSpec]
    truth_orbit: str | None
    truth_state: np.ndarray | None
    truth_dynamics: ComponentSpec | None
    custody: CustodyRule
    truth_maneuvers: ComponentSpec | None = None
    """[truth.maneuvers]: the truth's burn plan (a "maneuver-plan" component), None for a ballistic truth."""
    truth_grid_minutes: float = 5.0
    predict_every_hours: float = 0.0
    end_with_prediction: bool = True
    recording_frame: str = "synodic"
    measurements_file: Path | None = None
    measurements_reader: ComponentSpec | None = None
    observers: dict[str, ComponentSpec] = field(default_factory=dict)
    iod_observer: str = ""
    maneuvers: ManeuverSettings = field(default_factory=ManeuverSettings)
    source: str = "<memory>"
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def duration(self) -> float:
        """Duration in TU."""
        return float(units.days_to_tu(self.duration_days))

    def build(self, table: str, registry: Registry | None = None) -> Any:
        """The component for ``table`` ('dynamics', 'sensor', 'schedule', 'iod', 'filter'): the one
        validation built the first time, a fresh one after."""
        spec = self.components.get(table)
        if spec is None:
            return None
        return spec.build(registry or default_registry())

    def initial_truth(self, registry: Registry | None = None) -> np.ndarray:
        """Truth state at t = 0, (6,) nondimensional synodic."""
        if self.truth_state is not None:
            return self.truth_state.copy()
        orbit = (registry or default_registry()).create("orbit", self.truth_orbit)
        return np.asarray(orbit.state, dtype=float).copy()

    def with_overrides(self, overrides: dict[str, Any], registry: Registry | None = None,
                       source: str | None = None) -> "Scenario":
        """A new scenario with tables/keys replaced, e.g. {"filter": {"name": "ukf"}, "seed": 3}.

        A component table given with a different ``name`` replaces the table; with the same
        name (or no name) its keys are merged into it. The result is validated again.
        """
        return parse_scenario(_merge_overrides(self.raw, overrides), source or self.source, registry)


def _merge_overrides(raw: dict, overrides: dict[str, Any] | None) -> dict:
    """A copy of the scenario table ``raw`` with ``overrides`` applied (see ``with_overrides``)."""
    raw = copy.deepcopy(raw)
    for key, value in (overrides or {}).items():
        if key in COMPONENT_TABLES and isinstance(value, dict):
            old = raw.get(key, {})
            if "name" in value and value["name"] != old.get("name"):
                raw[key] = keep_choice_table(old, value)
            else:
                merged = dict(old)
                merged.update(value)
                raw[key] = merged
        else:
            raw[key] = copy.deepcopy(value)
    return raw


# -- loading -------------------------------------------------------------------------------------

def load_scenario(path_or_name: str | Path, registry: Registry | None = None,
                  overrides: dict[str, Any] | None = None) -> Scenario:
    """Read and validate a scenario file, or a built-in scenario by name; ``overrides`` (as for
    :meth:`Scenario.with_overrides`) are applied before the one validation."""
    if not str(path_or_name).strip():
        raise ConfigError("scenario: empty name; give a built-in scenario's name (cistrack scenarios lists them) or "
                          "the path of a scenario file")
    p = Path(path_or_name)
    if not p.exists() and p.suffix != ".toml" and "/" not in str(path_or_name):
        p = builtin_scenario_path(str(path_or_name))
    if p.is_dir():
        raise ConfigError(f"{p}: a directory, not a scenario file (a TOML file or a built-in scenario's name)")
    if not p.exists():
        raise ConfigError(f"scenario file not found: {p}")
    try:
        data = toml_input.loads(toml_input.read_file(p), str(p))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from None
    scen = parse_scenario(_merge_overrides(data, overrides) if overrides else data, str(p), registry)
    if scen.measurements_file is not None and not scen.measurements_file.is_absolute():
        scen.measurements_file = (relative_base(p) / scen.measurements_file).resolve()
    return scen


def recorded_scenario(p: Path, registry: Any = None) -> "Scenario":
    """The scenario a run or fit recorded in its results folder (``p``, its ``scenario.toml``),
    parsed: ConfigError naming the file when it is damaged (not TOML, not a file, not UTF-8, a
    scenario no longer valid), never a parser's traceback. FileNotFoundError when it is missing."""
    if not os.path.lexists(p):
        raise FileNotFoundError(p)
    try:
        data = toml_input.loads(toml_input.read_file(p), str(p))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: the results folder's record of its scenario is damaged (not valid TOML: {exc}); "
                          "run the scenario again into the folder with --overwrite") from None
    return parse_scenario(data, str(p), registry)


def relative_base(p: Path) -> Path:
    """The directory a file's relative paths are read from: its own, or the current directory for a
    pipe (``cistrack run <(...)``: its directory, /dev/fd, holds nothing of the user's)."""
    return p.parent if p.is_file() else Path.cwd()


def parse_scenario(data: dict, source: str = "<memory>", registry: Registry | None = None) -> Scenario:
    """Validate a scenario given as a dict (as read from TOML)."""
    reg = registry or default_registry()
    _check_tables(data, source, reg)
    data, choices = choose_tables(data, COMPONENT_TABLES, reg, source)  # [filter.pgm]-style sub-tables
    top, epoch_text = _top_level(data, source)
    truth = data.get("truth", {})
    if not isinstance(truth, dict):
        raise ConfigError(f"{source}: 'truth' must be a table")
    components, observers = _components(data, truth, source, reg, epoch_text)
    check_keys(truth, _TRUTH_KEYS, source, "[truth]")
    measurements_file, measurements_reader = _measurements(data, source, reg)
    truth_orbit, truth_state = _truth_start(truth, source, reg, measurements_file)
    truth_dyn = None
    if "dynamics" in truth:
        truth_dyn = component_spec(truth["dynamics"], "dynamics", "[truth.dynamics]", source, reg,
                                   epoch_text=epoch_text)
    truth_maneuvers = _truth_maneuvers(truth, source, reg, measurements_file)
    custody = custody_rule(data.get("custody", {}), source)
    run = _run_options(data, source, components, top, observers)
    maneuvers = maneuver_settings(data, components["filter"].name, source, reg)
    return Scenario(**top, components=components, truth_orbit=truth_orbit, truth_state=truth_state,
                    truth_dynamics=truth_dyn, truth_maneuvers=truth_maneuvers, custody=custody, **run, maneuvers=maneuvers,
                    measurements_file=measurements_file, measurements_reader=measurements_reader,
                    observers=observers, source=source, raw=recorded_tables(data, choices))


def _check_tables(data: Any, source: str, reg: Registry) -> None:
    """A table, not too deep, with known keys and the required component tables."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a scenario must be a TOML table")
    toml_input.check_depth(data, source)
    check_keys(data, _TOP_KEYS, source, "top level")
    for table in _REQUIRED_TABLES:
        if table not in data:
            raise ConfigError(f"{source}: missing table [{table}] (it names the {table} component, "
                              f"e.g. name = {example_name(reg, COMPONENT_TABLES[table])!r})")



def _epoch_value(value: Any, source: str) -> Any:
    """The scenario's ``epoch`` as written (an ISO-8601 UTC string or a TOML date-time); a TOML date
    without a time (``epoch = 2026-01-01``) is refused naming the forms that are taken."""
    if isinstance(value, date) and not isinstance(value, datetime):
        raise ConfigError(f"{source}: top level: key 'epoch' = {value.isoformat()} is a date without a time of "
                          f"day; give a UTC date-time: epoch = \"{value.isoformat()}T00:00:00Z\" (or the TOML date-time "
                          f"{value.isoformat()}T00:00:00Z)")
    return typed(value, (str, datetime), source, "top level", "epoch")

def _top_level(data: dict, source: str) -> tuple[dict[str, Any], Any]:
    """The top-level keys as Scenario fields (name, description, epoch, seed, duration_days), and
    the epoch as written (components that take an epoch are given it)."""
    name = check_path_component(typed(data.get("name", Path(source).stem), str, source, "top level", "name"),
                                f"{source}: top level: key 'name'")
    description = typed(data.get("description", ""), str, source, "top level", "description")
    epoch_text = _epoch_value(data.get("epoch", "2026-01-01T00:00:00Z"), source)
    try:
        epoch = units.parse_utc(epoch_text)
    except ValueError:
        raise ConfigError(f"{source}: top level: key 'epoch' = {quoted(epoch_text)} "
                          f"{units.utc_problem(epoch_text)}") from None
    check_epoch_span(epoch, 0.0, f"{source}: top level: key 'epoch'")
    seed = typed(data.get("seed", 0), int, source, "top level", "seed")
    check_seed(seed, f"{source}: top level: key 'seed'")
    duration = float(typed(data.get("duration_days", 7.0), (int, float), source, "top level", "duration_days"))
    if not np.isfinite(duration) or duration <= 0:
        raise ConfigError(f"{source}: top level: key 'duration_days' = {duration} must be a finite number > 0")
    return dict(name=name, description=description, epoch=epoch, seed=seed, duration_days=duration), epoch_text


def _components(data: dict, truth: dict, source: str, reg: Registry,
                epoch_text: Any) -> tuple[dict[str, ComponentSpec], dict]:
    """The component tables' specs (the first observer of [sensors] is the sensor), and the
    observers by name."""
    moving = truth.get("dynamics", data.get("dynamics"))   # what moves an observer in space
    components: dict[str, ComponentSpec] = {}
    for table, kind in COMPONENT_TABLES.items():
        if table in data:
            components[table] = component_spec(data[table], kind, f"[{table}]", source, reg,
                                                epoch_text=epoch_text, dynamics_table=moving)
    observers = observer_specs(data, source, reg, epoch_text, moving)
    if observers:
        components["sensor"] = next(iter(observers.values()))
    return components, observers


def _measurements(data: dict, source: str, reg: Registry) -> tuple[Path | None, ComponentSpec | None]:
    """[measurements]: the observation file (as written) and its reader's spec, or None."""
    meas = data.get("measurements", {})
    if not isinstance(meas, dict):
        raise ConfigError(f"{source}: 'measurements' must be a table")
    check_keys(meas, _MEAS_KEYS, source, "[measurements]")
    measurements_file = Path(typed(meas["file"], str, source, "[measurements]", "file")) if "file" in meas else None
    measurements_reader = None
    if "reader" in meas:
        if measurements_file is None:
            raise ConfigError(f"{source}: [measurements]: key 'reader' needs 'file'")
        measurements_reader = component_spec(meas["reader"], "reader", "[measurements.reader]", source, reg)
    return measurements_file, measurements_reader


def _truth_start(truth: dict, source: str, reg: Registry,
                 measurements_file: Path | None) -> tuple[str | None, np.ndarray | None]:
    """[truth]: the registered orbit's name, or the start state (nondimensional synodic, (6,))
    from ``state_km``; neither only with an observation file."""
    truth_orbit = truth.get("orbit")
    if truth_orbit is not None and "state_km" in truth:
        raise ConfigError(f"{source}: [truth]: give either 'orbit' or 'state_km', not both")
    if truth_orbit is not None:
        typed(truth_orbit, str, source, "[truth]", "orbit")
        try:
            obj = reg.get("orbit", truth_orbit).factory
        except UnknownComponentError as exc:
            raise ConfigError(f"{source}: [truth]: key 'orbit': {exc}") from None
        if not isinstance(obj, ReferenceOrbit):
            raise ConfigError(f"{source}: [truth]: orbit {truth_orbit!r} is not a ReferenceOrbit")
        return truth_orbit, None
    if "state_km" in truth:
        st = truth["state_km"]
        if (not isinstance(st, list) or len(st) != 6
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in st)
                or not np.all(np.isfinite(np.asarray(st, dtype=float)))):
            raise ConfigError(f"{source}: [truth]: key 'state_km' must be 6 finite numbers "
                              f"[x, y, z (km), vx, vy, vz (km/s)] in the synodic barycentric frame")
        return None, units.state_from_km(np.asarray(st, dtype=float))
    if measurements_file is None:
        raise ConfigError(f"{source}: [truth] needs 'orbit' (one of: {', '.join(reg.names('orbit')) or 'none registered'})"
                          f" or 'state_km', unless [measurements] file = ... gives real observations")
    return None, None


def _truth_maneuvers(truth: dict, source: str, reg: Registry, measurements_file: Path | None) -> ComponentSpec | None:
    """[truth.maneuvers]: the burns the simulated truth flies (a maneuver-plan component table,
    docs/maneuvers.md), or None. Refused with observations from a file: there is no simulated truth."""
    if "maneuvers" not in truth:
        return None
    if measurements_file is not None:
        raise ConfigError(f"{source}: [truth.maneuvers] plans burns of a simulated truth, but [measurements] "
                          "file = ... gives real observations (no truth is simulated); remove one of the two")
    return component_spec(truth["maneuvers"], "maneuver-plan", "[truth.maneuvers]", source, reg)


def _run_options(data: dict, source: str, components: dict[str, ComponentSpec], top: dict[str, Any],
                 observers: dict) -> dict[str, Any]:
    """[run] as Scenario fields, after refusing sizes that cannot fit or take too long."""
    run = data.get("run", {})
    if not isinstance(run, dict):
        raise ConfigError(f"{source}: 'run' must be a table")
    check_keys(run, _RUN_KEYS, source, "[run]")
    grid = float(typed(run.get("truth_grid_minutes", 5.0), (int, float), source, "[run]", "truth_grid_minutes"))
    if not 0 < grid <= 120:
        raise ConfigError(f"{source}: [run]: key 'truth_grid_minutes' = {grid} must lie in (0, 120]")
    pe = float(typed(run.get("predict_every_hours", 0.0), (int, float), source, "[run]", "predict_every_hours"))
    if not (np.isfinite(pe) and pe >= 0):
        raise ConfigError(f"{source}: [run]: key 'predict_every_hours' = {pe} must be a finite number >= 0 "
                          "(0: only at measurements)")
    duration = top["duration_days"]
    _check_sizes(components, duration, grid, source)
    check_epoch_span(top["epoch"], duration, f"{source}: top level: key 'epoch'")
    if pe > 0:
        check_steps(duration * 24.0 / pe, f"{source}: [run]: key 'predict_every_hours' = {pe:g}",
                    f"a prediction every {pe:g} h over duration_days = {duration:g}")
    ewp = typed(run.get("end_with_prediction", True), bool, source, "[run]", "end_with_prediction")
    iod_obs = typed(run.get("iod_observer", next(iter(observers), "")), str, source, "[run]", "iod_observer")
    if iod_obs and iod_obs not in observers:
        raise ConfigError(f"{source}: [run]: key 'iod_observer' = {quoted(iod_obs)} names no [sensors] table; "
                          f"observers: {', '.join(observers) or '(none: the scenario has one [sensor])'}")
    rframe = typed(run.get("recording_frame", "synodic"), str, source, "[run]", "recording_frame")
    if rframe not in ("synodic", "inertial"):
        raise ConfigError(f"{source}: [run]: key 'recording_frame' = {quoted(rframe)} must be 'synodic' (the rotating "
                          "frame) or 'inertial' (the sensor's Earth-centred inertial frame)")
    return dict(truth_grid_minutes=grid, predict_every_hours=pe, end_with_prediction=ewp,
                recording_frame=rframe, iod_observer=iod_obs)


# -- validation helpers --------------------------------------------------------------------------

# Moved to cistrack.interfaces.component (issue 26); kept here for code that imported them.
from cistrack.interfaces.component import BYTES_PER_PARTICLE, IOD_CHUNK_BYTES  # noqa: E402,F401


def _number(v: Any) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _check_sizes(components: dict[str, ComponentSpec], duration_days: float, grid_minutes: float,
                 source: str) -> None:
    """Refuse particle counts and durations whose arrays cannot fit in the available memory, and
    more mixture components than particles."""
    n_grid = duration_days * 1440.0 / grid_minutes + 1
    check_memory(n_grid * 6 * 8 * 4, f"{source}: top level: key 'duration_days' = {duration_days:g}",
                 f"the truth on a {grid_minutes:g}-minute grid ({n_grid:.3g} points)")
    for table, spec in components.items():
        need = spec.memory_need()
        if need is None:
            continue
        check_memory(need.bytes, f"{source}: [{table}]: key '{need.parameter}' = {need.value:g}",
                     f"{spec.name!r} with {need.what}")
        n = need.value
        m = _number(spec.params.get("n_components"))
        if m is not None and need.parameter == "n_particles" and m > n:
            raise ConfigError(f"{source}: [{table}]: key 'n_components' = {m:g} must be <= n_particles ({n:g})")
