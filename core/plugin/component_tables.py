"""Validating one component table of a scenario: registry look-up, parameter types, nesting.

A table ``{name = "pgm", n_particles = 1000, clusterer = {name = "kmeans"}}`` becomes a
:class:`ComponentSpec` after checking that the name is registered for the kind, that every key
is a constructor parameter, and that each value has the parameter's annotated type (converted
where lossless; a parameter typed as a component, such as ``clusterer``, becomes a nested spec,
also when the table leaves it at a default naming a component: every component of a run is
built through the run's registry).
The component is constructed once during validation, so its own value checks run before anything
else, and that instance is the one the run uses. A sensor with an ``epoch`` parameter receives
the scenario's epoch (the one special case: the epoch is a property of the scenario).
"""
from __future__ import annotations

import copy
import inspect
import types
import typing
from dataclasses import dataclass, field
from typing import Any

from cistrack import units
from cistrack.interfaces.component import Component, param_specs
from cistrack.errors import CistrackError, ConfigError, ParameterError, UnknownComponentError, exception_text, quoted
from cistrack.interrupts import plugin_fault
from cistrack.plugin.registry import Registry

__all__ = ["ComponentSpec", "component_spec", "check_keys", "typed", "example_name"]


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

    def memory_need(self) -> Any:
        """The validated component's :meth:`~cistrack.interfaces.component.Component.memory_need`
        (None before validation or for objects that are not components)."""
        held = self._validated[1] if self._validated is not None else None
        ask = getattr(held, "memory_need", None)
        return ask() if callable(ask) else None

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


def example_name(reg: Registry, kind: str) -> str:
    names = reg.names(kind)
    return names[0] if names else "..."


def check_keys(table: dict, allowed: set[str], source: str, where: str) -> None:
    for key in table:
        if key not in allowed:
            msg = f"{source}: {where}: unknown key {quoted(key)}; allowed keys: {', '.join(sorted(allowed))}"
            import difflib  # on use: only an unknown name needs it

            close = difflib.get_close_matches(key, list(allowed), n=1)
            if close:
                msg += f". Did you mean {close[0]!r}?"
            raise ConfigError(msg)


def typed(value: Any, types_: Any, source: str, where: str, key: str) -> Any:
    tt = types_ if isinstance(types_, tuple) else (types_,)
    ok = isinstance(value, tt) and not (isinstance(value, bool) and bool not in tt)
    if not ok:
        names = " or ".join(t.__name__ for t in tt)
        raise ConfigError(f"{source}: {where}: key {key!r} = {quoted(value)} has type {type(value).__name__}; expected {names}")
    return value


def component_spec(table: Any, kind: str, where: str, source: str, reg: Registry,
                    epoch_text: Any = None, dynamics_table: Any = None) -> ComponentSpec:
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
    _set_scenario_epoch(params, kind, specs, epoch_text, source, where)
    out: dict[str, Any] = {}
    if kind == "sensor" and "dynamics" in specs and _union_component_kind(specs["dynamics"].annotation) == "dynamics":
        # A sensor that moves under the run's dynamics (a space telescope) gets the scenario's
        # model (and, through it, the epoch) unless its table names its own.
        dyn = params.pop("dynamics", dynamics_table)
        if dyn is not None:
            out["dynamics"] = component_spec(dyn, "dynamics", f"{where[:-1]}.dynamics]" if where.endswith("]")
                                             else f"{where}.dynamics", source, reg, epoch_text=epoch_text)
    shared = dict(getattr(factory, "nested_params", None) or {})
    # nested components last, so that the values handed on to them are checked and converted first
    for key, value in sorted(params.items(), key=lambda kv: kv[0] in shared):
        if key not in specs:
            _unknown_parameter(key, specs, f"{source}: {where}: unknown parameter {quoted(key)} for {kind} {name!r}")
        value = _hand_on(_named_default(value, specs[key]), shared.get(key, ()), out, specs, specs[key].annotation, reg)
        out[key] = _coerce(value, specs[key].annotation, source, f"{where}", key, reg)
    for key, ps in specs.items():
        # A parameter that names another component by default (e.g. the PGM's clusterer = "kmeans")
        # is resolved here, through this scenario's registry, not later by the component itself.
        if key not in out and isinstance(ps.default, str) and _union_component_kind(ps.annotation):
            value = _hand_on(ps.default, shared.get(key, ()), out, specs, ps.annotation, reg)
            out[key] = _coerce(value, ps.annotation, source, f"{where}", key, reg)
    spec = ComponentSpec(kind, name, out, f"{source}: {where}")
    spec._validated = (reg, _build(spec, reg))  # value checks before anything runs; kept for the run
    return spec


def _named_default(value: Any, ps: Any) -> Any:
    """``value``, or, for a table of parameters without a ``name`` given to a parameter whose
    default is a component by name (``--set filter.clusterer.n_init=2`` on a filter whose clusterer
    is the default "kmeans"), that table of the default component."""
    if isinstance(value, dict) and "name" not in value and isinstance(ps.default, str) \
            and _union_component_kind(ps.annotation):
        return {"name": ps.default, **value}
    return value


def _set_scenario_epoch(params: dict, kind: str, specs: dict, epoch_text: Any, source: str, where: str) -> None:
    """A sensor or dynamics model with an ``epoch`` parameter gets the scenario's epoch (UTC
    text); its table may not set it."""
    if kind in ("sensor", "dynamics") and "epoch" in specs:
        if "epoch" in params:
            raise ConfigError(f"{source}: {where}: key 'epoch' is set by the scenario's top-level 'epoch'; "
                              f"remove it from {where}")
        if epoch_text is not None:
            params["epoch"] = units.format_utc(units.parse_utc(epoch_text))


def _unknown_parameter(key: str, specs: dict, what: str) -> None:
    """Raise the error for a key that is not a constructor parameter: the allowed ones, and the
    closest name."""
    msg = f"{what}; allowed: {', '.join(specs) or '(none)'}"
    import difflib  # on use: only an unknown name needs it

    close = difflib.get_close_matches(key, list(specs), n=1)
    if close:
        msg += f". Did you mean {close[0]!r}?"
    raise ConfigError(msg)


def _hand_on(table: Any, names: tuple[str, ...], out: dict, specs: dict, ann: Any, reg: Registry) -> Any:
    """The nested component table ``table`` (a name or a table) with the outer component's
    parameters ``names`` added (its value in ``out``, else its default) where the nested
    component takes them and its table does not set them (see ``Component.nested_params``)."""
    kind = _union_component_kind(ann) or _component_kind(ann)
    if not names or not kind or not isinstance(table, (str, dict)):
        return table
    nested = {"name": table} if isinstance(table, str) else dict(table)
    try:
        factory = reg.get(kind, str(nested.get("name"))).factory
    except (UnknownComponentError, TypeError):
        return table  # an unknown name: _coerce reports it
    takes = param_specs(factory) if isinstance(factory, type) else {}
    for name in names:
        value = out.get(name, specs[name].default if name in specs else None)
        if name in takes and name not in nested and value is not None:
            nested[name] = value
    return nested


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
    except BaseException as exc:  # a plugin's own failure (a missing optional library, a bug, sys.exit)
        if not plugin_fault(exc):
            raise
        raise ConfigError(f"{spec.where}: {reg.describe(spec.kind, spec.name)}: could not be constructed: "
                          f"{exception_text(exc)}") from exc


def _union_component_kind(ann: Any) -> str | None:
    """The component kind of an annotation such as ``Clusterer | str`` (None for other types)."""
    if typing.get_origin(ann) in (typing.Union, types.UnionType):
        return next((k for k in (_component_kind(a) for a in typing.get_args(ann)) if k), None)
    return None


def _component_kind(ann: Any) -> str | None:
    if isinstance(ann, type) and issubclass(ann, Component) and ann.kind:
        return ann.kind
    return None


def _coerce(value: Any, ann: Any, source: str, where: str, key: str, reg: Registry) -> Any:
    """Check ``value`` (from TOML) against the type annotation ``ann``; convert where lossless."""
    if ann is Any or ann is inspect.Parameter.empty:
        return value
    origin = typing.get_origin(ann)
    args = typing.get_args(ann)
    if origin in (typing.Union, types.UnionType):
        return _coerce_union(value, args, source, where, key, reg)
    kind = _component_kind(ann)
    if kind:
        return component_spec(value, kind, f"{where[:-1]}.{key}]" if where.endswith("]") else where, source, reg)
    loc = f"{source}: {where}: key {key!r}"
    if any(ann is t for t in _SCALARS):
        return _coerce_scalar(value, ann, loc)
    if origin in (list, tuple, typing.Sequence) or ann in (list, tuple):
        return _coerce_sequence(value, origin, args, source, where, key, reg)
    if origin is dict or ann is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{loc} = {quoted(value)} has type {type(value).__name__}; expected a table")
        return value
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{loc} = {quoted(value)}; allowed: {', '.join(map(repr, args))}")
        return value
    return value


def _coerce_union(value: Any, args: tuple, source: str, where: str, key: str, reg: Registry) -> Any:
    """A union: a component-typed parameter (e.g. ``Clusterer | str``) takes a name string or a
    table with 'name'; otherwise the first member type the value passes."""
    comp_kinds = [k for k in (_component_kind(a) for a in args) if k]
    if comp_kinds and (isinstance(value, dict) or isinstance(value, str)):
        return component_spec(value, comp_kinds[0], f"{where}.{key}" if not where.endswith("]")
                              else f"{where[:-1]}.{key}]", source, reg)
    shaped = None  # the error of the member whose shape the value has (an array's bad element)
    for a in args:
        if a is type(None):
            continue
        try:
            return _coerce(value, a, source, where, key, reg)
        except ConfigError as exc:
            if shaped is None and isinstance(value, list) and _is_array_type(a):
                shaped = exc
    if shaped is not None:
        raise shaped
    expected = " or ".join(_type_name(a) for a in args if a is not type(None))
    raise ConfigError(f"{source}: {where}: key {key!r} = {quoted(value)}: expected {expected}")


def _is_array_type(a: Any) -> bool:
    import collections.abc

    return typing.get_origin(a) in (list, tuple, collections.abc.Sequence) or a in (list, tuple)


_SCALARS: dict[type, str] = {float: "a number", int: "an integer", bool: "true or false", str: "a string"}
"""Scalar annotation -> what the message says is expected."""


def _coerce_scalar(value: Any, ann: type, loc: str) -> Any:
    """A float (an int converted), an int, a bool or a str; a bool is never a number."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    ok = {float: number, int: isinstance(value, int) and not isinstance(value, bool),
          bool: isinstance(value, bool), str: isinstance(value, str)}[ann]
    if not ok:
        raise ConfigError(f"{loc} = {quoted(value)} has type {type(value).__name__}; expected {_SCALARS[ann]}")
    return float(value) if ann is float else value


def _coerce_sequence(value: Any, origin: Any, args: tuple, source: str, where: str, key: str, reg: Registry) -> Any:
    """An array: a list (``list[T]``, ``Sequence[T]``), a tuple of fixed length (``tuple[A, B]``)
    or of any length (``tuple[T, ...]``), each element coerced to its type."""
    if not isinstance(value, list):
        raise ConfigError(f"{source}: {where}: key {key!r} = {quoted(value)} has type {type(value).__name__}; expected an array")
    if args and not (origin is tuple and len(args) == 2 and args[1] is Ellipsis):
        if origin is tuple:
            if len(args) != len(value):
                raise ConfigError(f"{source}: {where}: key {key!r}: expected {len(args)} values, got {len(value)}")
            return tuple(_coerce(v, a, source, where, f"{key}[{i}]", reg) for i, (v, a) in enumerate(zip(value, args)))
        return [_coerce(v, args[0], source, where, f"{key}[{i}]", reg) for i, v in enumerate(value)]
    if origin is tuple and args:
        return tuple(_coerce(v, args[0], source, where, f"{key}[{i}]", reg) for i, v in enumerate(value))
    return list(value)


def _type_name(a: Any) -> str:
    if _component_kind(a):
        return f"a {_component_kind(a)} component (name or table)"
    return getattr(a, "__name__", str(a))

