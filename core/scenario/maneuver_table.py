"""The ``[maneuvers]`` table of a scenario: the maneuver detector, the response and the estimate.

    [maneuvers]
    detector = "nis-window"        # a maneuver-detector component (name or table), "auto" or "none"
    response = "inflate"           # a maneuver-response component, or "none" (the default)
    estimate = true                # delta-v of each detection by least squares at the end of the run

Without the table (or with ``detector = "auto"``, or a detector table without a ``name``: the
parameters of the automatic choice) every run watches for maneuvers with the detector suited to its
filter: ``mixture-likelihood`` for a PGM (a Gaussian mixture belief),
``nis-window`` otherwise (where the registry has them); no response, and the estimate.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from cistrack.errors import ConfigError
from cistrack.plugin.component_tables import ComponentSpec, check_keys, component_spec, typed
from cistrack.plugin.registry import Registry

__all__ = ["ManeuverSettings", "maneuver_settings", "AUTO_DETECTOR"]

_KEYS = {"detector", "response", "estimate"}
AUTO_DETECTOR = {"mixture": "mixture-likelihood", "gaussian": "nis-window"}
"""The detector ``auto`` picks: for a PGM filter (its name starts with "pgm"), else."""


@dataclass
class ManeuverSettings:
    """The validated ``[maneuvers]`` table: the detector's and response's specs (None: none)."""

    detector: ComponentSpec | None = None
    response: ComponentSpec | None = None
    estimate: bool = True
    asked: bool = False
    """The scenario's ``[maneuvers]`` table names the detector or sets its parameters (it is not
    the default watch every run keeps)."""


def _auto(filter_name: str, reg: Registry, source: str, params: dict | None = None) -> ComponentSpec | None:
    name = AUTO_DETECTOR["mixture" if filter_name.startswith("pgm") else "gaussian"]
    if name not in reg.names("maneuver-detector"):
        return None
    return component_spec({"name": name, **(params or {})}, "maneuver-detector",
                          f"[maneuvers] detector (auto: {name!r})", source, reg)


def _component(value: Any, kind: str, where: str, source: str, reg: Registry) -> ComponentSpec | None:
    if value == "none":
        return None
    return component_spec(value, kind, where, source, reg)


def maneuver_settings(data: dict, filter_name: str, source: str, reg: Registry) -> ManeuverSettings:
    """``[maneuvers]`` of the scenario ``data`` checked (ConfigError naming the key)."""
    table = data.get("maneuvers", {})
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: 'maneuvers' must be a table (keys: {', '.join(sorted(_KEYS))})")
    check_keys(table, _KEYS, source, "[maneuvers]")
    det = table.get("detector", "auto")
    if det == "auto" or (isinstance(det, dict) and det.get("name", "auto") == "auto"):
        params = {k: v for k, v in det.items() if k != "name"} if isinstance(det, dict) else {}
        detector = _auto(filter_name, reg, source, params)
    else:
        detector = _component(det, "maneuver-detector", "[maneuvers] detector", source, reg)
    response = _component(table.get("response", "none"), "maneuver-response", "[maneuvers] response", source, reg)
    if response is not None and detector is None:
        raise ConfigError(f"{source}: [maneuvers]: a response ({response.name!r}) needs a detector; "
                          "set detector to 'auto' or a maneuver-detector")
    estimate = typed(table.get("estimate", True), bool, source, "[maneuvers]", "estimate")
    return ManeuverSettings(detector, response, bool(estimate), "detector" in table)
