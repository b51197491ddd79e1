"""One table per component choice: ``[filter.pgm]``, ``[filter.ukf]`` under ``[filter]``.

A component table may hold, beside ``name`` and parameters, a sub-table named after a
registered component of its kind with that component's parameters::

    [filter]
    name = "pgm"          # switching to "ukf" needs no other edit

    [filter.pgm]
    n_particles = 10000

    [filter.ukf]
    alpha = 0.5

Only the sub-table of the component named is read; those of the kind's other components wait
until ``name`` names them. A parameter written in the component table itself applies to
whichever component is named and wins over its sub-table (``--set filter.KEY=VALUE`` writes
there); the two may not give one parameter different values (the sub-table's would be ignored).
A key that is neither is refused as an unknown parameter, as before.
"""
from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

from cistrack.errors import ConfigError, UnknownComponentError, quoted

if TYPE_CHECKING:
    from cistrack.plugin.registry import Registry

__all__ = ["choose_tables", "recorded_tables", "keep_choice_table"]


def choose_tables(data: dict, tables: dict[str, str], reg: Registry, source: str) -> tuple[dict, dict[str, dict]]:
    """``data`` (a scenario as read from TOML) with each component table of ``tables`` (table ->
    registry kind) holding the keys of its named component only (its sub-table merged in under
    the table's own keys), and, by table, the non-empty sub-tables of the kind's other components."""
    out = dict(data)
    others: dict[str, dict] = {}
    for table, kind in tables.items():
        if table in data:
            out[table], others[table] = _choose(data[table], kind, reg, source, table)
    return out, others


def recorded_tables(data: dict, others: dict[str, dict]) -> dict:
    """A copy of the chosen ``data`` with the other components' sub-tables put back: what a run
    records, and what ``--set TABLE.name=...`` switches between."""
    out = copy.deepcopy(data)
    for table, subs in others.items():
        if subs and isinstance(out.get(table), dict):
            out[table] = {**out[table], **copy.deepcopy(subs)}
    return out


def _choose(table: Any, kind: str, reg: Registry, source: str, where: str) -> tuple[Any, dict]:
    """The table with its named component's sub-table merged in, and the other sub-tables; a
    table whose name is missing or unknown is returned unchanged (its validation reports that)."""
    if not isinstance(table, dict) or not isinstance(table.get("name"), str):
        return table, {}
    name = table["name"]
    try:
        factory = reg.get(kind, name).factory
    except UnknownComponentError:
        return table, {}
    from cistrack.interfaces.component import param_specs

    takes = param_specs(factory) if isinstance(factory, type) else {}
    choices = set(reg.names(kind)) - set(takes)  # a parameter of the same name stays a parameter
    own: dict[str, Any] = {}
    rest: dict[str, Any] = {}
    others: dict[str, Any] = {}
    for key, value in table.items():
        if key not in choices:
            rest[key] = value
        elif not isinstance(value, dict):
            raise ConfigError(f"{source}: [{where}]: key {key!r} = {quoted(value)}: a key named after the {kind} {key!r} "
                              f"holds its parameters and must be a table, [{where}.{key}]")
        elif key == name:
            own = value
        elif value:
            others[key] = value
    if "name" in own:
        raise ConfigError(f"{source}: [{where}.{name}]: key 'name': the {kind} is named in [{where}] itself; "
                          "remove it here")
    _refuse_conflicts(rest, own, source, where, name)
    chosen = dict(rest)  # the table's own keys first ('name' leads), and they win
    for key, value in copy.deepcopy(own).items():
        chosen.setdefault(key, value)
    return chosen, copy.deepcopy(others)


def _refuse_conflicts(table: dict[str, Any], own: dict[str, Any], source: str, where: str, name: str) -> None:
    """ConfigError when the named component's sub-table sets a parameter that the table itself
    sets to another value: the table's would win, and the sub-table's (a ``--set``, a study's
    sweep) would be dropped without a word."""
    clash = sorted(k for k in own if k in table and table[k] != own[k])
    if clash:
        k = clash[0]
        raise ConfigError(f"{source}: [{where}] {k} = {quoted(table[k])} and [{where}.{name}] {k} = {quoted(own[k])}: a parameter "
                          f"in [{where}] wins over [{where}.{name}], so the second would be ignored; set it in one "
                          f"place (--set {where}.{k}=VALUE writes in [{where}])")


def keep_choice_table(old: Any, new: dict[str, Any]) -> dict[str, Any]:
    """A copy of the component table ``new``, which names another component than ``old`` does,
    with ``old``'s sub-table for the newly named component kept (see the module docstring)."""
    out = copy.deepcopy(new)
    name = new.get("name")
    if isinstance(old, dict) and isinstance(name, str) and isinstance(old.get(name), dict) and name not in out:
        out[name] = copy.deepcopy(old[name])
    return out
