"""What observes in each scenario of a study, in words: the architecture column of a report.

A scenario with one ``[sensor]`` is that sensor; one with ``[sensors.<key>]`` tables is the
network of them. Ground telescopes are named with their site, space telescopes with their orbit
and phase (or "state" for one given by ``state_km``)."""
from __future__ import annotations

from typing import Any

from cistrack.scenario.loading import load_scenario

__all__ = ["describe_observer", "scenario_architecture", "architectures_of"]


def describe_observer(table: dict) -> str:
    """One observer's sensor table in words, e.g. "space-telescope on dro-2-1 at phase 0.5"."""
    name = str(table.get("name", "?"))
    if "orbit" in table or "state_km" in table or name == "space-telescope":
        where = (f"on {table['orbit']} at phase {float(table.get('phase', 0.0)):g}" if table.get("orbit")
                 else "from a given state" if "state_km" in table else "on dro-2-1 at phase 0")
        return f"{name} {where}"
    if "latitude_deg" in table or "longitude_deg" in table:
        return f"{name} at ({float(table.get('latitude_deg', 0.0)):.2f}, {float(table.get('longitude_deg', 0.0)):.2f}) deg"
    return name


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
