"""A commented scenario file to start from: what ``cistrack init [NAME]`` writes.

The values are the built-in ``example-1`` scenario's; every key it sets is explained in a comment
above it, and every other parameter of its components is listed commented out with its default,
type, unit and meaning (from the components' own docstrings, :mod:`cistrack.plugin.param_docs`,
the same source as ``cistrack plugins NAME``), so that uncommenting a line is all it takes to
change it. The file runs as written: ``cistrack run NAME.toml``.
"""
from __future__ import annotations

import dataclasses
import shlex
import sys
import textwrap
from pathlib import Path
from typing import Any

import tomli_w

from cistrack.errors import ConfigError
from cistrack.evaluation.custody import CustodyRule
from cistrack.plugin.param_docs import param_docs, summary_of
from cistrack.plugin.registry import Registry, default_registry
from cistrack.results.atomic_files import write_text_new
from cistrack.scenario.builtin_scenarios import builtin_scenario_path
from cistrack.scenario.limits import PATH_COMPONENT_RULE, check_path_component
from cistrack.scenario.loading import COMPONENT_TABLES, Scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["TEMPLATE_SOURCE", "scenario_template", "write_scenario_template", "template_path"]

#: The built-in scenario whose values the template holds.
TEMPLATE_SOURCE = "example-1"
_WIDTH = 96

_TOP: dict[str, str] = {
    "name": f"The scenario's name: the first part of each run's id, so one folder name ({PATH_COMPONENT_RULE}).",
    "description": "One line saying what the scenario is for.",
    "epoch": "UTC of t = 0 (ISO 8601); times in results are days since this epoch.",
    "seed": "The default seed of a run (cistrack run --seed N overrides it); the same seed gives the same numbers.",
    "duration_days": "How long the run lasts, days from the epoch.",
}
_TRUTH = ("The true orbit: it makes the simulated measurements, and custody, NEES and errors are judged "
          "against it. orbit = a registered reference orbit ({orbits}), or state_km = [x, y, z, vx, vy, vz] "
          "(km, km/s, synodic barycentric frame) instead; dynamics = {{ name = ... }} propagates the truth "
          "with other dynamics than [dynamics].")
_RUN: dict[str, str] = {  # key -> meaning; the defaults are the Scenario's
    "predict_every_hours": "Prediction-only steps between passes every this many hours, for the entropy "
                           "curve (0: steps only at measurements).",
    "truth_grid_minutes": "Spacing of the truth's propagated grid, minutes, in (0, 120].",
    "end_with_prediction": "End the run with a prediction to duration_days after the last measurement.",
    "recording_frame": "Frame of a rerun recording: \"synodic\" (the rotating frame) or \"inertial\".",
}
#: component table -> the other components whose (commented) parameter tables the file lists too
_ALTERNATIVES: dict[str, tuple[str, ...]] = {"filter": ("ukf", "enkf")}
_MEASUREMENTS = ("Real observations instead of simulated ones (then [truth] may go): file = \"obs.csv\" and "
                 "optionally reader = {{ name = ... }} (docs/measurements.md).")


def _comment(text: str, indent: str = "") -> list[str]:
    return [f"{indent}# {line}" for line in textwrap.wrap(text, _WIDTH - len(indent) - 2)] or [f"{indent}#"]


def _value(v: Any) -> str | None:
    """``v`` in TOML syntax, or None when TOML cannot hold it (None, objects)."""
    try:
        return tomli_w.dumps({"v": v}).partition("=")[2].strip()
    except TypeError:
        return None


def _component_lines(table: str, given: dict[str, Any], reg: Registry) -> list[str]:
    """[TABLE] naming the component, then [TABLE.NAME] with its parameters (and, for a table with
    :data:`_ALTERNATIVES`, the others' tables with every parameter at its default)."""
    kind = COMPONENT_TABLES[table]
    name = given["name"]
    entry = reg.get(kind, name)
    others = ", ".join(n for n in reg.names(kind) if n != name)
    lines = [""] + _comment(f"[{table}]: the {kind}. {summary_of(entry.factory)}") + [f"[{table}]"]
    lines += _comment(f"A registered {kind}" + (f" (others: {others})" if others else "")
                      + f"; cistrack plugins {name} describes every parameter.") + [f"name = {_value(name)}"]
    switch = " or ".join(f'"{n}"' for n in _ALTERNATIVES.get(table, ()) if n in reg.names(kind))
    lines += _comment(f"Each {kind}'s parameters go in its own table, [{table}.NAME]: only the table of the {kind} "
                      f"named above is read, so changing name{f' (to {switch}, say)' if switch else ''} needs no "
                      f"other edit. A parameter written in [{table}] itself applies to whichever {kind} is named.")
    params = {k: v for k, v in given.items() if k != "name"}
    for other in [name] + [n for n in _ALTERNATIVES.get(table, ()) if n != name and n in reg.names(kind)]:
        lines += [""] + _comment(f"[{table}.{other}]: the parameters of the {kind} {other!r}"
                                 + (" (read only when name is changed to it)." if other != name else "."))
        lines += [f"[{table}.{other}]"] + _param_lines(reg.get(kind, other).factory, params if other == name else {})
    return lines


def _param_lines(factory: Any, given: dict[str, Any]) -> list[str]:
    """Each parameter of ``factory`` explained in a comment: ``key = value`` for those ``given``,
    commented out at its default for the others."""
    lines: list[str] = []
    previous = ""
    for p in (param_docs(factory) if isinstance(factory, type) else []):
        if p.name == "epoch":
            continue  # the scenario's epoch is injected
        unit = f", {p.unit}" if p.unit else ""
        head = f"{p.name} ({p.type}{unit})"
        meaning = p.meaning or "(undocumented)"
        if p.name in given:
            lines += _comment(f"{head}: {meaning}") + [f"{p.name} = {_value(given[p.name])}"]
            previous = ""
            continue
        default = _value(p.default) if not p.required else None
        text = meaning if meaning != previous else "(as above)"
        lines += _comment(f"{head}: {text}")
        lines.append(f"# {p.name} = {default}" if default is not None else
                     f"# {p.name} = ...   (default: {'required' if p.required else repr(p.default)})")
        previous = meaning
    return lines


def scenario_template(name: str = "my-scenario", registry: Registry | None = None) -> str:
    """The commented scenario text (TOML) named ``name``, with the values of :data:`TEMPLATE_SOURCE`."""
    reg = registry or default_registry()
    name = check_path_component(name, "the scenario name")
    data = tomllib.loads(builtin_scenario_path(TEMPLATE_SOURCE).read_text())
    data["name"] = name
    data["description"] = f"My scenario, started from the built-in {TEMPLATE_SOURCE}: {data.get('description', '')}"
    lines = _comment(f"A cistrack scenario, written by 'cistrack init' from the built-in {TEMPLATE_SOURCE}. "
                     f"Run it with: cistrack run {shlex.quote(name + '.toml')} (--seed N, --set TABLE.KEY=VALUE change one value "
                     "without editing). Lines '# key = value' are parameters left at their default: "
                     "uncomment one to change it. cistrack plugins lists every component.")
    for key, doc in _TOP.items():
        lines += [""] + _comment(doc) + [f"{key} = {_value(data[key])}"]
    truth = data.get("truth", {})
    lines += [""] + _comment(_TRUTH.format(orbits=", ".join(reg.names("orbit")))) + ["[truth]"]
    lines += [f"{k} = {_value(v)}" for k, v in truth.items()]
    for table in COMPONENT_TABLES:
        if table in data:
            lines += _component_lines(table, data[table], reg)
    run = data.get("run", {})
    lines += [""] + _comment("[run]: how the run steps.") + ["[run]"]
    defaults = {f.name: f.default for f in dataclasses.fields(Scenario)}
    for key, doc in _RUN.items():
        lines += _comment(doc) + [f"{key} = {_value(run[key])}" if key in run else f"# {key} = {_value(defaults[key])}"]
    lines += [""] + _comment("[custody]: the thresholds of the verdict (tracking, not-converged, lost, diverged); "
                             "the defaults are these (cistrack.evaluation.custody.CustodyRule).") + ["# [custody]"]
    lines += [f"# {k} = {_value(v)}" for k, v in vars(CustodyRule()).items() if _value(v) is not None]
    lines += [""] + _comment(_MEASUREMENTS.format()) + ["# [measurements]", '# file = "obs.csv"']
    return "\n".join(lines) + "\n"


def template_path(name: str | None) -> Path:
    """The file ``cistrack init NAME`` writes: NAME, with ``.toml`` added when it has no such suffix
    (in any case: ``x.TOML`` is written as it is).

    ConfigError for a NAME whose file name (without ``.toml``), the scenario's name, could not name
    the scenario's run folders: the rule of :func:`~cistrack.scenario.limits.check_path_component`,
    stated in the message. Any other character is taken (``cistrack init "x y;z"`` writes
    ``x y;z.toml``)."""
    p = Path("my-scenario" if name is None else name)
    if name is not None and (p.name in ("", ".", "..") or name.endswith(("/", "\\"))):
        raise ConfigError(f"cistrack init NAME {name!r}: names a folder, not a scenario file; give a file name "
                          f"such as {(p / 'my-scenario').as_posix()}")
    has_suffix = p.suffix.lower() == ".toml"
    try:
        check_path_component(p.stem if has_suffix else p.name, f"cistrack init NAME {name!r}: the scenario name")
    except ConfigError as exc:
        raise ConfigError(f"{exc}; give a name such as my-scenario (optionally in a folder: runs/my-scenario)") from None
    return p if has_suffix else p.with_name(p.name + ".toml")


def write_scenario_template(name: str | None = None, registry: Registry | None = None) -> Path:
    """Write :func:`scenario_template` to :func:`template_path` (``name``) and return the path.

    Raises ConfigError when the file exists (it is never overwritten) or cannot be written.
    """
    path = template_path(name)
    text = scenario_template(path.stem, registry)
    try:
        write_text_new(path, text)  # whole or absent: a full disk leaves no empty file to block a retry
    except FileExistsError:
        raise ConfigError(f"{path} exists: cistrack init never overwrites a file; give another name "
                          "or remove it first") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write it ({exc.strerror or exc})") from None
    return path
