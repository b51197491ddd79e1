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
import difflib
import inspect
import sys
import types
import typing
from dataclasses import dataclass, field
from datetime import datetime
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from . import units
from .component import Component, param_specs
from .custody import CustodyRule
from .limits import check_memory, check_path_component, check_seed
from .errors import CistrackError, ConfigError, ParameterError, UnknownComponentError
from .interfaces import ReferenceOrbit
from .registry import Registry, default_registry

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Scenario", "ComponentSpec", "CustodyRule", "load_scenario", "parse_scenario",
           "builtin_scenarios", "builtin_scenario_path", "COMPONENT_TABLES"]

COMPONENT_TABLES: dict[str, str] = {
    "dynamics": "dynamics", "sensor": "sensor", "schedule": "schedule", "iod": "iod", "filter": "filter",
}
"""Scenario table -> registry kind of the component it builds."""

_TOP_KEYS = {"name", "description", "epoch", "seed", "duration_days", "truth", "custody", "run",
             "measurements", *COMPONENT_TABLES}
_REQUIRED_TABLES = ("dynamics", "sensor", "iod", "filter")
_TRUTH_KEYS = {"orbit", "state_km", "dynamics"}
_CUSTODY_KEYS = {"loglik_threshold", "hdr_threshold", "hdr_consecutive"}
_RUN_KEYS = {"truth_grid_minutes", "predict_every_hours", "end_with_prediction"}
_MEAS_KEYS = {"file", "reader"}


@dataclass
class ComponentSpec:
    """A validated component table: registry kind and name, parameters, where it was written.

    Validation constructs the component once (so value checks run before anything else); the
    first :meth:`build` with the same registry hands out that instance, later calls construct
    fresh ones. So a run builds each component exactly once.
    """

    kind: str
    name: str
    params: dict[str, Any]
    where: str
    _validated: Any = field(default=None, init=False, repr=False, compare=False)

    def build(self, registry: Registry) -> Any:
        """The component: the instance made during validation (once), else a new one."""
        held, self._validated = self._validated, None
        if held is not None and held[0] is registry:
            return held[1]
        return _build(self, registry)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_validated"] = None  # an instance is never shipped to another process
        return state

    def __deepcopy__(self, memo) -> "ComponentSpec":
        return ComponentSpec(self.kind, self.name, copy.deepcopy(self.params, memo), self.where)


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
    truth_grid_minutes: float = 5.0
    predict_every_hours: float = 0.0
    end_with_prediction: bool = True
    measurements_file: Path | None = None
    measurements_reader: ComponentSpec | None = None
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
                raw[key] = copy.deepcopy(value)
            else:
                merged = dict(old)
                merged.update(value)
                raw[key] = merged
        else:
            raw[key] = copy.deepcopy(value)
    return raw


# -- loading -------------------------------------------------------------------------------------

def builtin_scenario_path(name: str) -> Path:
    """Path of the built-in scenario ``name`` (file ``cistrack/scenarios/<name>.toml``)."""
    base = resources.files("cistrack.scenarios")
    p = base / f"{name}.toml"
    if not p.is_file():
        avail = sorted(builtin_scenarios())
        msg = f"no built-in scenario {name!r}; built-in scenarios: {', '.join(avail)}"
        close = difflib.get_close_matches(name, avail, n=1)
        if close:
            msg += f". Did you mean {close[0]!r}?"
        raise ConfigError(msg)
    return Path(str(p))


def builtin_scenarios() -> dict[str, str]:
    """Built-in scenario names -> one-line descriptions."""
    out = {}
    base = resources.files("cistrack.scenarios")
    for entry in sorted(base.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            try:
                data = tomllib.loads(entry.read_text())
                out[entry.name[:-5]] = str(data.get("description", "")).strip().splitlines()[0] \
                    if data.get("description") else ""
            except tomllib.TOMLDecodeError:
                out[entry.name[:-5]] = "(unreadable)"
    return out


def load_scenario(path_or_name: str | Path, registry: Registry | None = None,
                  overrides: dict[str, Any] | None = None) -> Scenario:
    """Read and validate a scenario file, or a built-in scenario by name; ``overrides`` (as for
    :meth:`Scenario.with_overrides`) are applied before the one validation."""
    p = Path(path_or_name)
    if not p.exists() and p.suffix != ".toml" and "/" not in str(path_or_name):
        p = builtin_scenario_path(str(path_or_name))
    if not p.exists():
        raise ConfigError(f"scenario file not found: {p}")
    try:
        data = tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{p}: cannot read: {exc}") from None
    scen = parse_scenario(_merge_overrides(data, overrides) if overrides else data, str(p), registry)
    if scen.measurements_file is not None and not scen.measurements_file.is_absolute():
        scen.measurements_file = (p.parent / scen.measurements_file).resolve()
    return scen


def parse_scenario(data: dict, source: str = "<memory>", registry: Registry | None = None) -> Scenario:
    """Validate a scenario given as a dict (as read from TOML)."""
    reg = registry or default_registry()
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a scenario must be a TOML table")
    _check_keys(data, _TOP_KEYS, source, "top level")
    for table in _REQUIRED_TABLES:
        if table not in data:
            raise ConfigError(f"{source}: missing table [{table}] (it names the {table} component, "
                              f"e.g. name = {_example_name(reg, COMPONENT_TABLES[table])!r})")
    name = check_path_component(_typed(data.get("name", Path(source).stem), str, source, "top level", "name"),
                                f"{source}: top level: key 'name'")
    description = _typed(data.get("description", ""), str, source, "top level", "description")
    epoch_text = _typed(data.get("epoch", "2026-01-01T00:00:00Z"), (str, datetime), source, "top level", "epoch")
    try:
        epoch = units.parse_utc(epoch_text)
    except ValueError:
        raise ConfigError(f"{source}: top level: key 'epoch' = {epoch_text!r} is not an ISO-8601 UTC time "
                          f"(e.g. '2026-01-01T00:00:00Z')") from None
    seed = _typed(data.get("seed", 0), int, source, "top level", "seed")
    check_seed(seed, f"{source}: top level: key 'seed'")
    duration = float(_typed(data.get("duration_days", 7.0), (int, float), source, "top level", "duration_days"))
    if not np.isfinite(duration) or duration <= 0:
        raise ConfigError(f"{source}: top level: key 'duration_days' = {duration} must be > 0")

    components: dict[str, ComponentSpec] = {}
    for table, kind in COMPONENT_TABLES.items():
        if table in data:
            components[table] = _component_spec(data[table], kind, f"[{table}]", source, reg,
                                                epoch_text=epoch_text)

    truth = data.get("truth", {})
    if not isinstance(truth, dict):
        raise ConfigError(f"{source}: 'truth' must be a table")
    _check_keys(truth, _TRUTH_KEYS, source, "[truth]")
    truth_orbit = truth.get("orbit")
    truth_state = None
    meas = data.get("measurements", {})
    if not isinstance(meas, dict):
        raise ConfigError(f"{source}: 'measurements' must be a table")
    _check_keys(meas, _MEAS_KEYS, source, "[measurements]")
    measurements_file = Path(_typed(meas["file"], str, source, "[measurements]", "file")) if "file" in meas else None
    measurements_reader = None
    if "reader" in meas:
        if measurements_file is None:
            raise ConfigError(f"{source}: [measurements]: key 'reader' needs 'file'")
        measurements_reader = _component_spec(meas["reader"], "reader", "[measurements.reader]", source, reg)
    if truth_orbit is not None and "state_km" in truth:
        raise ConfigError(f"{source}: [truth]: give either 'orbit' or 'state_km', not both")
    if truth_orbit is not None:
        _typed(truth_orbit, str, source, "[truth]", "orbit")
        try:
            obj = reg.get("orbit", truth_orbit).factory
        except UnknownComponentError as exc:
            raise ConfigError(f"{source}: [truth]: key 'orbit': {exc}") from None
        if not isinstance(obj, ReferenceOrbit):
            raise ConfigError(f"{source}: [truth]: orbit {truth_orbit!r} is not a ReferenceOrbit")
    elif "state_km" in truth:
        st = truth["state_km"]
        if (not isinstance(st, list) or len(st) != 6
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in st)
                or not np.all(np.isfinite(np.asarray(st, dtype=float)))):
            raise ConfigError(f"{source}: [truth]: key 'state_km' must be 6 finite numbers "
                              f"[x, y, z (km), vx, vy, vz (km/s)] in the synodic barycentric frame")
        truth_state = units.state_from_km(np.asarray(st, dtype=float))
    elif measurements_file is None:
        raise ConfigError(f"{source}: [truth] needs 'orbit' (one of: {', '.join(reg.names('orbit')) or 'none registered'})"
                          f" or 'state_km', unless [measurements] file = ... gives real observations")
    truth_dyn = None
    if "dynamics" in truth:
        truth_dyn = _component_spec(truth["dynamics"], "dynamics", "[truth.dynamics]", source, reg)

    cust = data.get("custody", {})
    if not isinstance(cust, dict):
        raise ConfigError(f"{source}: 'custody' must be a table")
    _check_keys(cust, _CUSTODY_KEYS, source, "[custody]")
    custody = CustodyRule(
        loglik_threshold=float(_typed(cust.get("loglik_threshold", -100.0), (int, float), source, "[custody]", "loglik_threshold")),
        hdr_threshold=float(_typed(cust.get("hdr_threshold", 0.997), (int, float), source, "[custody]", "hdr_threshold")),
        hdr_consecutive=_typed(cust.get("hdr_consecutive", 2), int, source, "[custody]", "hdr_consecutive"),
    )
    if not 0 < custody.hdr_threshold < 1:
        raise ConfigError(f"{source}: [custody]: key 'hdr_threshold' = {custody.hdr_threshold} must lie in (0, 1)")
    if custody.hdr_consecutive < 1:
        raise ConfigError(f"{source}: [custody]: key 'hdr_consecutive' must be >= 1")
    run = data.get("run", {})
    if not isinstance(run, dict):
        raise ConfigError(f"{source}: 'run' must be a table")
    _check_keys(run, _RUN_KEYS, source, "[run]")
    grid = float(_typed(run.get("truth_grid_minutes", 5.0), (int, float), source, "[run]", "truth_grid_minutes"))
    if not 0 < grid <= 120:
        raise ConfigError(f"{source}: [run]: key 'truth_grid_minutes' = {grid} must lie in (0, 120]")
    pe = float(_typed(run.get("predict_every_hours", 0.0), (int, float), source, "[run]", "predict_every_hours"))
    if not (np.isfinite(pe) and pe >= 0):
        raise ConfigError(f"{source}: [run]: key 'predict_every_hours' = {pe} must be a finite number >= 0 "
                          "(0: only at measurements)")
    _check_sizes(components, duration, grid, source)
    ewp = _typed(run.get("end_with_prediction", True), bool, source, "[run]", "end_with_prediction")
    return Scenario(name=name, description=description, epoch=epoch, seed=seed, duration_days=duration,
                    components=components, truth_orbit=truth_orbit, truth_state=truth_state,
                    truth_dynamics=truth_dyn, custody=custody, truth_grid_minutes=grid,
                    predict_every_hours=pe, end_with_prediction=ewp,
                    measurements_file=measurements_file, measurements_reader=measurements_reader,
                    source=source, raw=copy.deepcopy(data))


# -- validation helpers --------------------------------------------------------------------------

BYTES_PER_PARTICLE = 1024
"""Rough memory per particle of a filter or IOD sample (its state, propagation outputs, cluster
responsibilities and temporaries): used only to refuse sizes that cannot fit before allocating."""


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
        n = _number(spec.params.get("n_particles"))
        if n is None:
            continue
        factor = _number(spec.params.get("oversampling")) or (5.0 if table == "iod" else 1.0)
        check_memory(n * factor * BYTES_PER_PARTICLE, f"{source}: [{table}]: key 'n_particles' = {n:g}",
                     f"{spec.name!r} with {n:.3g} particles" + (f" (x{factor:g} oversampling)" if factor != 1 else ""))
        m = _number(spec.params.get("n_components"))
        if m is not None and m > n:
            raise ConfigError(f"{source}: [{table}]: key 'n_components' = {m:g} must be <= n_particles ({n:g})")

def _example_name(reg: Registry, kind: str) -> str:
    names = reg.names(kind)
    return names[0] if names else "..."


def _check_keys(table: dict, allowed: set[str], source: str, where: str) -> None:
    for key in table:
        if key not in allowed:
            msg = f"{source}: {where}: unknown key {key!r}; allowed keys: {', '.join(sorted(allowed))}"
            close = difflib.get_close_matches(key, list(allowed), n=1)
            if close:
                msg += f". Did you mean {close[0]!r}?"
            raise ConfigError(msg)


def _typed(value: Any, types_: Any, source: str, where: str, key: str) -> Any:
    tt = types_ if isinstance(types_, tuple) else (types_,)
    ok = isinstance(value, tt) and not (isinstance(value, bool) and bool not in tt)
    if not ok:
        names = " or ".join(t.__name__ for t in tt)
        raise ConfigError(f"{source}: {where}: key {key!r} = {value!r} has type {type(value).__name__}; expected {names}")
    return value


def _component_spec(table: Any, kind: str, where: str, source: str, reg: Registry,
                    epoch_text: Any = None) -> ComponentSpec:
    if isinstance(table, str):
        table = {"name": table}
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: {where} must be a table with a 'name' key (or a name string)")
    if "name" not in table:
        raise ConfigError(f"{source}: {where}: missing key 'name'; available {kind} components: "
                          f"{', '.join(reg.names(kind))}")
    name = table["name"]
    try:
        registration = reg.get(kind, name)
    except UnknownComponentError as exc:
        raise ConfigError(f"{source}: {where}: key 'name': {exc}") from None
    factory = registration.factory
    params = {k: v for k, v in table.items() if k != "name"}
    if not isinstance(factory, type):
        if params:
            raise ConfigError(f"{source}: {where}: {kind} {name!r} takes no parameters")
        return ComponentSpec(kind, name, {}, f"{source}: {where}")
    specs = param_specs(factory)
    if kind == "sensor" and "epoch" in specs:
        if "epoch" in params:
            raise ConfigError(f"{source}: {where}: key 'epoch' is set by the scenario's top-level 'epoch'; "
                              f"remove it from {where}")
        if epoch_text is not None:
            params["epoch"] = units.format_utc(units.parse_utc(epoch_text))
    out: dict[str, Any] = {}
    for key, value in params.items():
        if key not in specs:
            allowed = ", ".join(specs) or "(none)"
            msg = f"{source}: {where}: unknown parameter {key!r} for {kind} {name!r}; allowed: {allowed}"
            close = difflib.get_close_matches(key, list(specs), n=1)
            if close:
                msg += f". Did you mean {close[0]!r}?"
            raise ConfigError(msg)
        out[key] = _coerce(value, specs[key].annotation, source, f"{where}", key, reg)
    spec = ComponentSpec(kind, name, out, f"{source}: {where}")
    spec._validated = (reg, _build(spec, reg))  # value checks before anything runs; kept for the run
    return spec


def _build(spec: ComponentSpec, reg: Registry) -> Any:
    params = {k: (v.build(reg) if isinstance(v, ComponentSpec) else v) for k, v in spec.params.items()}
    try:
        return reg.create(spec.kind, spec.name, **params)
    except ParameterError as exc:
        raise ConfigError(f"{spec.where}: {exc}") from None
    except CistrackError:
        raise
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{spec.where}: {spec.kind} {spec.name!r} rejected its parameters: {exc}") from None


def _component_kind(ann: Any) -> str | None:
    if isinstance(ann, type) and issubclass(ann, Component) and ann.kind:
        return ann.kind
    return None


def _coerce(value: Any, ann: Any, source: str, where: str, key: str, reg: Registry) -> Any:
    """Check ``value`` (from TOML) against the type annotation ``ann``; convert where lossless."""
    loc = f"{source}: {where}: key {key!r}"
    if ann is Any or ann is inspect.Parameter.empty:
        return value
    origin = typing.get_origin(ann)
    args = typing.get_args(ann)
    if origin in (typing.Union, types.UnionType):
        # component-typed parameter (e.g. Clusterer | str): a name string or a table with 'name'
        comp_kinds = [k for k in (_component_kind(a) for a in args) if k]
        if comp_kinds and (isinstance(value, dict) or isinstance(value, str)):
            return _component_spec(value, comp_kinds[0], f"{where}.{key}" if not where.endswith("]")
                                   else f"{where[:-1]}.{key}]", source, reg)
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _coerce(value, a, source, where, key, reg)
            except ConfigError as exc:
                errors.append(str(exc))
        expected = " or ".join(_type_name(a) for a in args if a is not type(None))
        raise ConfigError(f"{loc} = {value!r}: expected {expected}")
    kind = _component_kind(ann)
    if kind:
        return _component_spec(value, kind, f"{where[:-1]}.{key}]" if where.endswith("]") else where, source, reg)
    if ann is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected a number")
    if ann is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected an integer")
    if ann is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected true or false")
    if ann is str:
        if isinstance(value, str):
            return value
        raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected a string")
    if origin in (list, tuple, typing.Sequence) or ann in (list, tuple):
        if not isinstance(value, list):
            raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected an array")
        if args and not (origin is tuple and len(args) == 2 and args[1] is Ellipsis):
            if origin is tuple:
                if len(args) != len(value):
                    raise ConfigError(f"{loc}: expected {len(args)} values, got {len(value)}")
                return tuple(_coerce(v, a, source, where, f"{key}[{i}]", reg) for i, (v, a) in enumerate(zip(value, args)))
            return [_coerce(v, args[0], source, where, f"{key}[{i}]", reg) for i, v in enumerate(value)]
        if origin is tuple and args:
            return tuple(_coerce(v, args[0], source, where, f"{key}[{i}]", reg) for i, v in enumerate(value))
        return list(value)
    if origin is dict or ann is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{loc} = {value!r} has type {type(value).__name__}; expected a table")
        return value
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{loc} = {value!r}; allowed: {', '.join(map(repr, args))}")
        return value
    return value


def _type_name(a: Any) -> str:
    if _component_kind(a):
        return f"a {_component_kind(a)} component (name or table)"
    return getattr(a, "__name__", str(a))

