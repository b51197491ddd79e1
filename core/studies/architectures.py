"""What observes in each scenario of a study, in words: the architecture column of a report.

A scenario with one ``[sensor]`` is that sensor; one with ``[sensors.<key>]`` tables is the
network of them. Ground telescopes are named with their site, space telescopes with their orbit
and phase (or "state" for one given by ``state_km``)."""
from __future__ import annotations

from typing import Any

from cistrack.errors import UnknownComponentError
from cistrack.interfaces.component import param_specs
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import load_scenario

__all__ = ["describe_observer", "scenario_architecture", "architectures_of"]


def describe_observer(table: dict) -> str:
    """One observer's sensor table in words, e.g. "space-telescope on dro-2-1 at phase 0.5"."""
    name = str(table.get("name", "?"))
    if "orbit" in table or "state_km" in table or name == "space-telescope":
        where = (f"on {table['orbit']} at phase {float(table.get('phase', 0.0)):g}" if table.get("orbit")
                 else "from a given state" if "state_km" in table else "on dro-2-1 at phase 0")
        return f"{name} {where}"
    site = _site(name, table)
    kind = next((f" ({table[k]})" for k in ("measurement", "angles") if k in table), "")
    return f"{name}{kind} at {site}" if site else name


def _site(name: str, table: dict) -> str:
    """"(lat, lon) deg" of a ground sensor's table, its defaults filling what the table leaves out."""
    try:
        specs = param_specs(default_registry().get("sensor", name).factory)
    except (UnknownComponentError, TypeError, ValueError):  # unknown or not a class: no site to name
        return ""
    if "latitude_deg" not in specs or "longitude_deg" not in specs:
        return ""
    lat = float(table.get("latitude_deg", specs["latitude_deg"].default))
    lon = float(table.get("longitude_deg", specs["longitude_deg"].default))
    return f"({lat:.2f}, {lon:.2f}) deg"


def scenario_architecture(raw: dict) -> str:
    """The observers of a scenario table ``raw`` (as read from TOML) in words."""
    if isinstance(raw.get("sensors"), dict):
        return " + ".join(f"{key}: {describe_observer(t)}" for key, t in raw["sensors"].items())
    return describe_observer(raw.get("sensor", {}))


def architectures_of(specs: Any) -> dict[str, str]:
    """Scenario name -> architecture for the run specs of a study (each scenario read once)."""
    out: dict[str, str] = {}
    for s in specs:
        if s.scenario_name not in out:
            out[s.scenario_name] = scenario_architecture(load_scenario(s.scenario, overrides=s.overrides).raw)
    return out
