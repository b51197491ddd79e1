"""Study files (TOML): finding a study by path or built-in name, reading and checking it, and
the seeds it runs (see :mod:`cistrack.studies.study` for the file's keys)."""
from __future__ import annotations

import difflib
import json
import re
from collections import Counter
import sys
from importlib import resources
from pathlib import Path
from typing import Any

from cistrack.errors import ConfigError
from cistrack.scenario import toml_input
from cistrack.scenario.limits import check_count, check_seed

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["builtin_studies", "load_study", "recorded_settings", "scenario_base", "study_source", "STUDY_KEYS", "study_sweep",
           "scenario_entry", "overrides_error", "variant_error", "sweep_error"]

STUDY_KEYS = {"name", "description", "scenarios", "filters", "iod", "seeds", "n_seeds", "first_seed", "overrides",
              "sweep"}
"""Keys allowed at the top of a study file."""
_STUDY_KEYS = STUDY_KEYS


def builtin_studies() -> dict[str, str]:
    """Built-in study names -> one-line descriptions."""
    base = resources.files("cistrack.scenarios") / "studies"
    out = {}
    for e in sorted(base.iterdir(), key=lambda e: e.name):
        if e.name.endswith(".toml"):
            out[e.name[:-5]] = str(tomllib.loads(e.read_text()).get("description", "")).strip()
    return out


def _study_path(path_or_name: str | Path) -> Path:
    p = Path(path_or_name)
    if p.exists():
        return p
    base = resources.files("cistrack.scenarios") / "studies" / f"{path_or_name}.toml"
    if base.is_file():
        return Path(str(base))
    avail = sorted(builtin_studies())
    msg = f"study not found: {path_or_name!r} is neither a file nor a built-in study ({', '.join(avail)})"
    close = difflib.get_close_matches(str(path_or_name), avail, n=1)
    if close:
        msg += f". Did you mean {close[0]!r}?"
    raise ConfigError(msg)


def _recorded(directory: Path) -> dict:
    """The ``study.json`` that ``study run`` wrote into a study results directory."""
    rec = directory / "study.json"
    if not rec.is_file():
        raise ConfigError(f"{directory}: a directory, but not a study results directory (it has no "
                          f"study.json); give a study TOML file, a built-in study name or the --out "
                          f"directory of a 'cistrack study run'")
    try:
        data = json.loads(rec.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{rec}: not a readable study record: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("run_seeds"), list):
        raise ConfigError(f"{rec}: not a study record written by 'cistrack study run' (no 'run_seeds' list)")
    return data


def study_source(path_or_name: str | Path) -> str:
    """The study file a study comes from: the file itself, a built-in study's file, or for a study
    results directory the file its ``study.json`` records."""
    p = _study_path(path_or_name)
    return str(_recorded(p).get("source", p)) if p.is_dir() else str(p)


def recorded_settings(path_or_name: str | Path) -> list[str] | None:
    """The ``--set`` items a study results directory was run with (ConfigError naming its
    ``study.json`` when they are not a list of texts); None for a study file or name."""
    p = Path(path_or_name)
    if not p.is_dir():
        return None
    settings = _recorded(p).get("settings") or []
    if not isinstance(settings, list) or not all(isinstance(s, str) for s in settings):
        raise ConfigError(f"{p / 'study.json'}: key 'settings' = {settings!r}: not a list of the TABLE.KEY=VALUE "
                          "texts the study was run with (--set)")
    return settings


def scenario_base(path_or_name: str | Path, p: Path) -> Path:
    """The file beside which a study's relative scenario paths are read: the study file ``p``, or
    for a study results directory the study file its record names (its ``study.json`` ``p`` when
    that file is gone)."""
    src = Path(study_source(path_or_name))
    return src if src.is_file() else p


def load_study(path_or_name: str | Path) -> tuple[dict, Path]:
    """Read and check a study file, or the definition recorded in a study results directory (its
    seeds are then the ones run). Returns (data, the file it was read from: the study file, or the
    directory's ``study.json``, which errors in the definition name)."""
    p = _study_path(path_or_name)
    if p.is_dir():
        rec, where = _recorded(p), p / "study.json"
        data = {k: v for k, v in rec.items() if k in _STUDY_KEYS and k not in ("n_seeds", "first_seed")}
        data["seeds"] = _study_seeds({"seeds": rec["run_seeds"]}, where, key="run_seeds")
        data.setdefault("name", p.name)
        return _checked(data, where), where
    try:
        data = toml_input.loads(toml_input.read_file(p), str(p))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from None
    return _checked(data, p), p


def _checked(data: dict, p: Path) -> dict:
    for k in data:
        if k not in _STUDY_KEYS:
            close = difflib.get_close_matches(k, list(_STUDY_KEYS), n=1)
            raise ConfigError(f"{p}: unknown key {k!r}; allowed: {', '.join(sorted(_STUDY_KEYS))}"
                              + (f". Did you mean {close[0]!r}?" if close else ""))
    if not data.get("scenarios"):
        raise ConfigError(f"{p}: key 'scenarios' must list at least one scenario")
    for key in ("filters", "iod"):
        if key in data and not (isinstance(data[key], list) and data[key]):
            raise ConfigError(f"{p}: key {key!r} = {data[key]!r}: give a list of at least one name or table, "
                              f"or leave {key!r} out to keep each scenario's own")
    _check_component_overrides(data, p)
    if "seeds" in data and ("n_seeds" in data or "first_seed" in data):
        raise ConfigError(f"{p}: give 'seeds', or 'n_seeds' (and optionally 'first_seed'), not both")
    keys = [k for k, _ in study_sweep(data, p)]
    for sc in data["scenarios"]:
        scenario_entry(sc, p, keys)
    return data


def _check_component_overrides(data: dict, p: Path) -> None:
    """ConfigError naming the study file and its ``[overrides]`` when that is not a table, sets the
    seed (the study's seeds would replace it), or when
    its ``filter`` or ``iod`` is neither a table of the component's parameters nor (without the
    study's list of them) a component's name: a list would otherwise replace it unseen."""
    ov = data.get("overrides", {})
    if not isinstance(ov, dict):
        raise ConfigError(f"{p}: key 'overrides' = {ov!r}: give a table of scenario settings")
    if "seed" in ov:  # each run's seed is the study's: this one had been dropped without a word (probe J9)
        raise ConfigError(f"{p}: key 'overrides', setting seed = {ov['seed']!r}: a study's runs take their seeds from "
                          "its key 'seeds' (or 'n_seeds' and 'first_seed', or --first-seed and --n-seeds), never from "
                          f"a scenario's seed; give seeds = [{ov['seed']!r}] instead")
    for table, key in (("filter", "filters"), ("iod", "iod")):
        value = ov.get(table)
        if value is None or isinstance(value, dict) or (isinstance(value, str) and key not in data):
            continue
        why = (f"the study's key {key!r} chooses the components, so give only their parameters, as a table"
               if isinstance(value, str) else "give a table of the component's parameters, or its name")
        raise ConfigError(f"{p}: key 'overrides', setting {table} = {value!r}: {why} "
                          f"([overrides.{table}] KEY = VALUE)")


_SWEEP_VALUE = (bool, int, float, str)


def _flat(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    """A sweep table's (dotted key, values) pairs; nested tables (``[sweep.truth.maneuvers]``) flattened."""
    out: list[tuple[str, object]] = []
    for k, v in table.items():
        key = f"{prefix}{k}"
        out += _flat(v, key + ".") if isinstance(v, dict) else [(key, v)]
    return out


_NOT_SWEPT = {"seed": "the study's seeds are 'seeds' (or --first-seed/--n-seeds)",
              "name": "the run names its scenario variants itself",
              "filter.name": "filters are the study's key 'filters'", "iod.name": "IOD methods are the study's key 'iod'"}
"""Settings a sweep may not vary, with what the study file uses instead: a swept seed or filter
would be overridden by the study's own seeds and filters, and the runs named for values they never had."""


def _check_sweepable(key: str, where: str) -> None:
    why = _NOT_SWEPT.get(key)
    if why:
        raise ConfigError(f"{where}: cannot be swept: {why}")


def study_sweep(data: dict, p: Path) -> list[tuple[str, list]]:
    """The study's ``sweep``: (dotted setting, its values) pairs in file order; [] without one.

    Each key is a setting in ``--set`` syntax (``truth.maneuvers.delta_v_ms``), each value a
    non-empty list of distinct numbers, strings or booleans; a ConfigError names the file and key."""
    table = data.get("sweep")
    if table is None:
        return []
    if not isinstance(table, dict) or not table:
        raise ConfigError(f"{p}: key 'sweep' must be a table of settings to lists of values, e.g. "
                          'sweep = {"truth.maneuvers.delta_v_ms" = [0.1, 1.0]}')
    out = []
    seen: set[str] = set()
    for key, values in _flat(table):
        where = f"{p}: key 'sweep', setting {key!r}"
        if not all(part.strip() == part and part for part in key.split(".")):
            raise ConfigError(f"{where}: not a dotted setting TABLE.KEY (as --set takes; no spaces around the parts)")
        _check_sweepable(key, where)
        if key in seen:
            raise ConfigError(f"{where}: the same setting as {key!r}; sweep each setting once")
        seen.add(key)
        if not isinstance(values, list) or not values:
            raise ConfigError(f"{where}: must be a non-empty list of values, got {values!r}")
        bad = [v for v in values if not isinstance(v, _SWEEP_VALUE)]
        if bad:
            raise ConfigError(f"{where}: values must be numbers, strings or booleans, got {bad[0]!r} (filters "
                              "and IOD variants are the keys 'filters' and 'iod')")
        if len({_sweep_key(v) for v in values}) != len(values):
            raise ConfigError(f"{where}: repeats a value; each value must appear once (it names runs; 2 and 2.0 "
                              "are the same number)")
        out.append((key, list(values)))
    return out


def _sweep_key(value: Any) -> tuple:
    """What makes two sweep values the same run: a boolean, else a number's value (2 is 2.0), else the text."""
    if isinstance(value, bool):
        return ("bool", value)
    if isinstance(value, (int, float)):
        return ("number", float(value))
    return ("text", value)


def scenario_entry(entry: object, p: Path, sweep_keys: list[str]) -> tuple[str, list[str]]:
    """A ``scenarios`` entry: (the scenario's name or path, the sweep settings that apply to it).

    An entry is a name or path (every sweep setting applies), or a table ``{name = ..., sweep = ...}``
    where ``sweep`` is true (every setting), false (none) or a list of the study's sweep settings."""
    if isinstance(entry, str):
        return entry, list(sweep_keys)
    if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
        raise ConfigError(f"{p}: entries of 'scenarios' must be names, paths or tables "
                          f"{{name = ..., sweep = ...}}, got {entry!r}")
    unknown = sorted(set(entry) - {"name", "sweep"})
    if unknown:
        raise ConfigError(f"{p}: scenario entry {entry['name']!r}: unknown key {unknown[0]!r}; allowed: name, sweep")
    which = entry.get("sweep", True)
    if isinstance(which, bool):
        return entry["name"], list(sweep_keys) if which else []
    if not isinstance(which, list) or not all(isinstance(k, str) for k in which):
        raise ConfigError(f"{p}: scenario entry {entry['name']!r}: key 'sweep' must be true, false or a list "
                          f"of the study's sweep settings, got {which!r}")
    other = [k for k in which if k not in sweep_keys]
    if other:
        raise ConfigError(f"{p}: scenario entry {entry['name']!r}: key 'sweep' names {other[0]!r}, which is not "
                          f"a setting of the study's 'sweep' ({', '.join(sweep_keys) or 'none'})")
    return entry["name"], [k for k in sweep_keys if k in which]


def _study_seeds(data: dict, p: Path, first_seed: int | None = None, n_seeds: int | None = None,
                 key: str = "seeds") -> list[int]:
    """The study's seeds: its ``seeds`` list, or ``n_seeds`` seeds from ``first_seed`` (default 1);
    ``first_seed`` / ``n_seeds`` given here (the CLI's ``--first-seed`` / ``--n-seeds``) replace the
    file's, and turn a ``seeds`` list into consecutive seeds from its first. ``key``: the name the
    file ``p`` gives the list (a study record's ``run_seeds``), for errors."""
    if "seeds" in data:
        if not isinstance(data["seeds"], list) or not data["seeds"]:
            raise ConfigError(f"{p}: key {key!r} must be a non-empty list of integers from 0 to 2**63-1")
        seeds = [check_seed(s, f"{p}: key {key!r}") for s in data["seeds"]]
        repeated = sorted(s for s, n in Counter(seeds).items() if n > 1)
        if repeated:
            raise ConfigError(f"{p}: key {key!r} repeats seed(s) {', '.join(map(str, repeated))}; each seed "
                              "must appear once (a seed names its runs)")
        if first_seed is None and n_seeds is None:
            return seeds
        first, count = seeds[0], len(seeds)
    else:
        first = check_seed(data.get("first_seed", 1), f"{p}: key 'first_seed'")
        count = check_count(data.get("n_seeds", 1), f"{p}: key 'n_seeds'", 1, 1_000_000)
    if first_seed is not None:
        first = check_seed(first_seed, "--first-seed")
    if n_seeds is not None:
        count = check_count(n_seeds, "--n-seeds", 1, 1_000_000)
    check_seed(first + count - 1, f"{p}: the last seed (first seed + number of seeds - 1)")
    return list(range(first, first + count))


def _blamed_settings(message: str, settings: list[tuple[str, object]]) -> list[tuple[str, object]]:
    """The ``settings`` (dotted key, value) that a scenario error ``message`` (``"<file>: top
    level: ..."`` or ``"<file>: [table]: ..."``) is about; [] for none."""
    top = [(k, v) for k, v in settings if "." not in k and f"'{k}'" in message]
    if ": top level: " in message:
        return top
    tables = {k.split(".", 1)[0] for k, _ in settings if "." in k} | {k for k, _ in settings if "." not in k}
    table = next((t for t in tables if f": [{t}]:" in message or f": [{t}." in message), None)
    if table is None:
        return []
    mine = [(k, v) for k, v in settings if k == table or k.startswith(table + ".")]
    named = [(k, v) for k, v in mine if f"'{k.rsplit('.', 1)[-1]}'" in message]
    return named or mine


def _without_source(message: str, scenario_source: str | Path) -> str:
    """``message`` without its leading ``"<scenario file>: "``."""
    return message.split(": ", 1)[1] if message.startswith(f"{scenario_source}: ") else message


def overrides_error(message: str, study: Path, overrides: dict, scenario_name: str,
                    scenario_source: str | Path, scenario_raw: dict | None = None) -> str | None:
    """A scenario's error under the study's ``[overrides]`` told against the study file: the file,
    the key ``overrides``, the setting(s) and the scenario they were applied to; None when the
    error is about none of the overrides (the scenario's own file, a variant, a sweep, --set). A
    table given whole (``foo = {bar = 1}``, ``truth = {maneuvers = ...}``) is blamed as given, with
    the keys of the scenario's own table (``scenario_raw``) it dropped by replacing it (probe J4:
    both had been blamed on the scenario file)."""
    blamed = _blamed_settings(message, _flat(overrides or {})) or _whole_tables(message, overrides or {})
    if not blamed:
        return None
    rest = _without_source(message, scenario_source)
    shown = ", ".join(f"{k} = {v!r}" for k, v in blamed)
    return (f"{study}: key 'overrides', setting {shown} (applied to scenario {scenario_name!r}, "
            f"{scenario_source}): {rest}{_dropped_note(blamed, scenario_raw or {})}")


def _whole_tables(message: str, overrides: dict) -> list[tuple[str, Any]]:
    """The tables of ``overrides`` given whole that a scenario error ``message`` names: as a key at
    the top level (``top level: unknown key 'foo'``) or as its table (``[truth] needs ...``)."""
    top = ": top level: " in message
    return [(k, v) for k, v in overrides.items()
            if isinstance(v, dict) and (f"'{k}'" in message if top else f": [{k}] " in message)]


def _dropped_note(blamed: list[tuple[str, Any]], scenario_raw: dict) -> str:
    """What the overrides' tables among ``blamed`` dropped of the scenario's own tables, which they
    replace whole (all but the component tables, whose keys merge), in words; "" for nothing."""
    from cistrack.scenario.loading import COMPONENT_TABLES

    notes = []
    for key, value in blamed:
        own = scenario_raw.get(key)
        if key in COMPONENT_TABLES or not isinstance(value, dict) or not isinstance(own, dict):
            continue
        dropped = [f"{k} = {v!r}" for k, v in own.items() if k not in value]
        if dropped:
            notes.append(f"; the override replaces the scenario's whole [{key}] table, so its {', '.join(dropped)} "
                         f"{'is' if len(dropped) == 1 else 'are'} dropped: give {'it' if len(dropped) == 1 else 'them'} "
                         f"in the override's {key} table too")
    return "".join(notes)


def variant_error(message: str, study: Path, entries: dict, scenario_name: str,
                  scenario_source: str | Path) -> str | None:
    """A scenario's error about its ``[filter]`` or ``[iod]`` table where the study's ``filters``
    or ``iod`` list replaced it (``entries``: table name -> the list's entry, or None), told
    against the study file: the file, the key, the entry and the scenario; None otherwise."""
    for table, key in (("filter", "filters"), ("iod", "iod")):
        entry = entries.get(table)
        if entry and (f": [{table}]:" in message or f": [{table}." in message):
            rest = _without_source(message, scenario_source)
            return (f"{study}: key '{key}', entry {entry!r} (applied to scenario {scenario_name!r}, "
                    f"{scenario_source}): {rest}")
    return None


def _named_setting(message: str, combo: tuple) -> tuple[str, Any] | None:
    """The setting of the sweep combination ``combo`` that a scenario error ``message`` names (its
    last part quoted in its table, or at the top level), or one under a table the error says lacks
    its component's name (a table the sweep made); None for none."""
    blamed = _blamed_settings(message, list(combo))
    named = [(k, v) for k, v in blamed if f"'{k.rsplit('.', 1)[-1]}'" in message]
    if named:
        return named[0]
    made = [(k, v) for k, v in blamed if f": [{k.rsplit('.', 1)[0]}]: missing key 'name'" in message]
    return made[0] if made else None


def _unknown_setting(rest: str, key: str) -> bool:
    """Whether a scenario error (``rest``) about the swept ``key`` says the scenario does not know it."""
    last = key.rsplit(".", 1)[-1]
    return (f"unknown key '{last}'" in rest or f"unknown parameter '{last}'" in rest
            or f"[{key.rsplit('.', 1)[0]}]: missing key 'name'" in rest)


def sweep_error(message: str, study: Path, combo: tuple, scenario_name: str,
                scenario_source: str | Path, entry: str = "") -> str | None:
    """A scenario's error about a setting of the sweep combination ``combo`` (pairs of dotted
    setting and value) told against the study file: the key ``sweep``, the setting and its value
    with why it is refused; where the scenario does not know the setting, that it does not apply
    there and how to leave the scenario out of it (its ``scenarios`` entry as written, ``entry``:
    a file's path, not the scenario's inner name). None when the error names none of the settings."""
    hit = _named_setting(message, combo)
    if hit is None:
        return None
    key, value = hit
    rest = _without_source(message, scenario_source)
    where = f"{study}: key 'sweep', setting {key!r}"
    if _unknown_setting(rest, key):
        return (f"{where} does not apply to scenario {scenario_name!r} ({scenario_source}: {rest}); give its "
                f"entry as a table {{name = {json.dumps(entry or scenario_name)}, sweep = false}} or sweep = [the settings that apply]")
    said = re.search(re.escape(f"'{key.rsplit('.', 1)[-1]}' = ") + r"\S+", rest)  # the value as the scenario wrote it (-1.0 for -1)
    why = rest[said.end():].strip().removeprefix("is invalid:").strip() if said else rest
    return f"{where}: value {value!r} is invalid: {why} (scenario {scenario_name!r}, {scenario_source})"
