"""``--set table.key=value`` overrides from the command line, for scenarios and studies.

Each setting is a dotted path into the scenario's TOML tables and a value in TOML syntax
(``filter.n_particles=20000``, ``filter.clusterer.name="kmeans"``, ``duration_days=2``); a value
that is not valid TOML is taken as a string (``filter.name=ukf``). Settings are merged into the
scenario's tables and the result is validated exactly like a file, so a wrong key or value is
refused with the table and key named. Setting a component's ``name`` to another component
(``filter.name=sir``) replaces that component's table (its other keys belonged to the old
component), with a warning naming the parameters dropped; the new component's own sub-table
(``[filter.sir]``) is kept, and parameters given with ``--set`` too apply to it.
"""
from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import Any, Iterable

from cistrack.errors import QUOTED_CHARACTERS, ConfigError, quoted, shown
from cistrack.scenario import toml_input
from cistrack.scenario.component_choice import keep_choice_table

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["parse_settings", "merge_settings", "apply_settings", "describe_settings", "settings_suffix"]


def settings_suffix(settings: Iterable[str] | None) -> str:
    """The part of a default results directory's name that tells ``--set`` items apart:
    ``"__set-"`` and 8 hex digits of the sha256 of the items (one a line, as given), or "" for
    none; ``cistrack run`` and ``cistrack study run`` both name their default directories so."""
    items = list(settings or [])
    if not items:
        return ""
    import hashlib

    return "__set-" + hashlib.sha256("\n".join(items).encode()).hexdigest()[:8]


def _value(text: str, item: str) -> Any:
    """The TOML value ``text`` of the setting ``item`` (a bare word: the string itself)."""
    try:
        return toml_input.loads(f"v = {text}", f"--set {item}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word: take it as a string


def _shown(item: str) -> str:
    """The setting ``item`` as a message shows it: whole when short, else its key and its value
    shortened (:func:`~cistrack.errors.quoted`)."""
    key, sep, text = item.partition("=")
    return f"{key}={shown(text)}" if sep and len(key) <= QUOTED_CHARACTERS else shown(item)


def parse_settings(items: Iterable[str] | None) -> dict[str, Any]:
    """``["filter.n_particles=500", "seed=3"]`` -> ``{"filter": {"n_particles": 500}, "seed": 3}``.
    Two items that give one key different values are refused naming both."""
    out: dict[str, Any] = {}
    given: dict[tuple[str, ...], str] = {}  # the item that set each key, for a conflict's message
    for item in items or []:
        key, sep, text = item.partition("=")
        path = [part.strip() for part in key.split(".")]
        if not sep or not all(path):
            raise ConfigError(f"--set {quoted(item)}: expected TABLE.KEY=VALUE (VALUE in TOML syntax), "
                              f"e.g. --set filter.n_particles=20000 or --set duration_days=2")
        node = out
        for i, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if isinstance(child, str):  # a component chosen by name, then one of its parameters
                child = node[part] = {"name": child}
                given[tuple(path[:i + 1]) + ("name",)] = given.pop(tuple(path[:i + 1]), item)
            if not isinstance(child, dict):
                raise ConfigError(f"--set {_shown(item)}: '{part}' was already set to a value, not a table")
            node = child
        _put(node, tuple(path), _value(text.strip(), _shown(item)), item, given)
    return out


def _same_value(a: Any, b: Any) -> bool:
    """Whether two settings give one value: equal, and of one type except a number written as an
    integer and as a float (``1`` and ``1.0``); ``true`` is not ``1``."""
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and not isinstance(b, bool):
        return a == b
    return a == b and type(a) is type(b)


def _put(node: dict[str, Any], path: tuple[str, ...], value: Any, item: str,
         given: dict[tuple[str, ...], str]) -> None:
    """Set ``path[-1]`` of the table ``node`` to ``value`` (the setting ``item``'s); ConfigError
    naming both items when an earlier one (in ``given``) gave that key a different value. A table
    value is merged key by key; a component's name given after its parameters joins them."""
    key, old = path[-1], node.get(path[-1])
    if isinstance(value, str) and isinstance(old, dict):
        path, node, key, old = path + ("name",), old, "name", old.get("name")
    if isinstance(value, dict) and isinstance(old, (dict, str)):
        if isinstance(old, str):
            old = node[key] = {"name": old}
            given[path + ("name",)] = given.pop(path, item)
        for k, v in value.items():
            _put(old, path + (k,), v, item, given)
        return
    if old is not None and not _same_value(old, value):
        first = ([given[path[:n]] for n in range(len(path), 0, -1) if path[:n] in given]  # it or a table above
                 + [v for p, v in given.items() if p[:len(path)] == path])[0]  # a key inside it: a table there
        raise ConfigError(f"--set {_shown(first)} and --set {_shown(item)}: two values for {'.'.join(path)}; "
                          "give one")
    node[key] = value
    given.setdefault(path, item)


def merge_settings(tables: dict[str, Any], settings: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``tables`` with ``settings`` merged in (a new component ``name`` replaces its table)."""
    out = copy.deepcopy(tables)
    for key, value in settings.items():
        old = out.get(key)
        if isinstance(value, dict) and isinstance(old, str) and "name" not in value:
            old = {"name": old}  # a component chosen by name in the file: these are its parameters
        if isinstance(value, dict) and isinstance(old, dict):
            if "name" in value and value["name"] != old.get("name"):
                out[key] = keep_choice_table(old, value)  # the new component's own [TABLE.NAME] stays
            else:
                out[key] = merge_settings(_yield_to(old, value), value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _yield_to(old: dict[str, Any], value: dict[str, Any]) -> dict[str, Any]:
    """``old`` (a table) without what ``value`` sets in the other place of a component choice: a
    parameter set in the table leaves the named component's sub-table (``[filter.pgm]``), one set
    in that sub-table leaves the table, so that the setting given wins wherever it is written
    (:mod:`cistrack.scenario.component_choice`)."""
    name = old.get("name")
    if not isinstance(name, str):
        return old
    out = dict(old)
    sub, new_sub = old.get(name), value.get(name)
    if isinstance(sub, dict):
        out[name] = {k: v for k, v in sub.items() if k not in value or isinstance(value[k], dict)}
    if isinstance(new_sub, dict):
        out = {k: v for k, v in out.items() if k not in new_sub or isinstance(v, dict)}
    return out


NESTED_COMPONENT_TABLES: dict[str, str] = {"truth.dynamics": "dynamics", "truth.maneuvers": "maneuver-plan"}
"""Component tables inside other tables (dotted path -> registry kind), besides the top-level
ones (:data:`cistrack.scenario.loading.COMPONENT_TABLES`)."""


def _warn_replaced(tables: dict[str, Any], settings: dict[str, Any], registry=None, where: str = "") -> None:
    """A UserWarning for each component table of ``tables`` whose component ``settings`` switch to
    another (``filter.name=sir``, ``truth.maneuvers.name=burns``: any table with a ``name``, at any
    depth), naming the parameters of the old table that are dropped with it (those the settings do
    not set again) and how to keep them. ``where``: the dotted path of ``tables`` ("" at the top).
    (``truth.maneuvers.name=burns`` had dropped the burn's keys without a word: probe I8.)"""
    import warnings

    from cistrack.plugin.registry import default_registry
    from cistrack.scenario.loading import COMPONENT_TABLES

    reg = registry or default_registry()
    for key, value in settings.items():
        table, old = f"{where}{key}", tables.get(key)
        if not isinstance(old, dict) or not isinstance(value, dict):
            continue
        name = value.get("name")
        if not isinstance(name, str) or name == old.get("name"):
            _warn_replaced(old, value, reg, f"{table}.")
            continue
        kind = COMPONENT_TABLES.get(table) or NESTED_COMPONENT_TABLES.get(table)
        choices = set(reg.names(kind)) if kind else set()
        dropped = [k for k in old if k != "name" and k not in value and k not in choices]
        if dropped:
            what = f"{kind} {old.get('name')!r}" if kind else f"{old.get('name')!r}"
            warnings.warn(UserWarning(f"--set {table}.name={name} replaces the scenario's [{table}] ({what}): "
                                      f"{_dropped_advice(table, name, old, dropped, reg, kind)}"), stacklevel=3)


def _dropped_advice(table: str, name: str, old: dict[str, Any], dropped: list[str], reg, kind: str) -> str:
    """``n_particles = 200, n_components = 2 dropped with it; 'sir' takes n_particles too: add --set
    filter.n_particles=200 to keep it`` (or that the new component takes none of them)."""
    from cistrack.interfaces.component import param_specs

    factory = reg.get(kind, name).factory if kind and name in reg.names(kind) else None
    takes = [k for k in dropped if isinstance(factory, type) and k in param_specs(factory)]
    said = f"{', '.join(f'{k} = {_toml(old[k])}' for k in dropped)} dropped with it"
    if not takes:
        return f"{said} ({name!r} takes none of them)" if factory is not None else said
    keep = " ".join(f"--set {table}.{k}={_toml(old[k])}" for k in takes)
    return f"{said}; {name!r} takes {', '.join(takes)} too: add {keep} to keep {'it' if len(takes) == 1 else 'them'}"


def _toml(value: Any) -> str:
    """``value`` as TOML writes it (an inline table or value), for a message."""
    import json

    return json.dumps(value) if not isinstance(value, dict) else "{...}"


def describe_settings(items: Iterable[str] | None) -> str:
    """The ``--set`` items as a message names them, a long value shortened."""
    return " ".join(f"--set {_shown(i)}" for i in items or [])


def apply_settings(scenario, items: Iterable[str] | None, registry=None):
    """The scenario with ``--set`` items applied and validated again (the scenario itself if none)."""
    from cistrack.scenario.loading import parse_scenario

    settings = parse_settings(items)
    if not settings:
        return scenario
    source = f"{scenario.source} ({describe_settings(items)})"
    _warn_replaced(scenario.raw, settings, registry)
    new = parse_scenario(merge_settings(scenario.raw, settings), source, registry)
    new.source = scenario.source  # errors above named the settings; the run records the merged tables
    if new.measurements_file is not None and not new.measurements_file.is_absolute():
        base = Path(scenario.source).parent if Path(scenario.source).exists() else Path.cwd()
        new.measurements_file = (base / new.measurements_file).resolve()
    return new
