"""The observers of a scenario: one ``[sensor]`` table, or several named ``[sensors.<key>]``
tables (ground sites and telescopes in space in one network, docs/space-observers.md)::

    [sensors.texas]
    name = "ground-telescope"
    angles = "radec"

    [sensors.dro]
    name = "space-telescope"
    orbit = "dro-2-1"
    phase = 0.5

Every observer measures the same components (a network fuses them), each plans its own
measurement times with the scenario's ``[schedule]``, and the IOD works from the measurements of
one of them (``[run] iod_observer``, default the first).
"""
from __future__ import annotations

from typing import Any

from cistrack.errors import ConfigError, shown
from cistrack.plugin.component_tables import ComponentSpec, component_spec
from cistrack.plugin.registry import Registry
from cistrack.scenario.limits import check_path_component

__all__ = ["observer_specs"]


def observer_specs(data: dict, source: str, reg: Registry, epoch_text: Any,
                   moving: Any) -> dict[str, ComponentSpec]:
    """The validated ``[sensors.<key>]`` tables of scenario ``data`` (key -> spec, in file
    order); {} when the scenario has a single ``[sensor]``. Refuses both forms at once, a table
    that is not a table, and observers measuring different components."""
    if "sensors" not in data:
        if "sensor" not in data:
            raise ConfigError(f"{source}: missing table [sensor] (it names the sensor component, e.g. "
                              f"name = 'ground-telescope'), or [sensors.<key>] tables for several observers")
        return {}
    if "sensor" in data:
        raise ConfigError(f"{source}: give either one [sensor] table or [sensors.<key>] tables, not both")
    tables = data["sensors"]
    if not isinstance(tables, dict) or not tables or not all(isinstance(v, dict) for v in tables.values()):
        raise ConfigError(f"{source}: [sensors] must hold one table per observer, e.g. [sensors.dro] "
                          f"name = 'space-telescope'")
    if "measurements" in data:
        raise ConfigError(f"{source}: [sensors] simulates several observers; observations read from a "
                          f"file name their sites and use one [sensor]")
    out: dict[str, ComponentSpec] = {}
    for key, table in tables.items():
        check_path_component(key, f"{source}: [sensors.{shown(key)}]")  # a long key shortened, as values are
        out[key] = component_spec(table, "sensor", f"[sensors.{shown(key)}]", source, reg, epoch_text=epoch_text,
                                  dynamics_table=moving)
    first_key = next(iter(out))
    names = _names(out[first_key])
    for key, spec in out.items():
        own = _names(spec)
        if own != names:
            raise ConfigError(f"{source}: [sensors.{key}] measures {', '.join(own)} but [sensors.{first_key}] "
                              f"{', '.join(names)}; a network fuses one set of components (ground telescopes "
                              f"take angles = 'radec' to join space telescopes)")
    return out


def _names(spec: ComponentSpec) -> tuple[str, ...]:
    """The components the sensor validation built measures."""
    return tuple(spec._validated[1].names)
