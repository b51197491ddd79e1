"""The scenarios shipped with cistrack (``cistrack/scenarios/*.toml``): names, one-line
descriptions and paths."""
from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path

from cistrack.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["builtin_scenario_path", "builtin_scenarios"]


def builtin_scenario_path(name: str) -> Path:
    """Path of the built-in scenario ``name`` (file ``cistrack/scenarios/<name>.toml``)."""
    base = resources.files("cistrack.scenarios")
    p = base / f"{name}.toml"
    if not p.is_file():
        avail = sorted(builtin_scenarios())
        msg = f"no built-in scenario {name!r}; built-in scenarios: {', '.join(avail)}"
        import difflib  # on use: only an unknown name needs it

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
