"""What a fit may replace in its results directory, checked before anything is computed.

``cistrack fit`` redoes an earlier fit of the same object in its directory (the way to refit after
new observations or other settings), but never, unless told to (``--overwrite``), the results of a
``cistrack run`` or a fit of another object: :func:`check_fit_replacing` refuses, naming the
directory and what is there.
"""
from __future__ import annotations

import json
from pathlib import Path

from cistrack.errors import ConfigError
from cistrack.results.store import MANIFEST

__all__ = ["check_fit_replacing", "FIT_RECORD"]

FIT_RECORD = "fit.json"
"""The record a finished fit writes last in its directory."""


def _earlier(d: Path, designation: str) -> str:
    """What ``d`` holds that a fit of ``designation`` must not replace, or "" (nothing, or a fit of it)."""
    record = d / FIT_RECORD
    if record.is_file():
        try:
            earlier = json.loads(record.read_text(encoding="utf-8")).get("designation")
        except (OSError, ValueError, AttributeError) as exc:
            return f"a fit record that cannot be read ({exc})"
        return "" if earlier == designation else f"the fit of another object, {earlier!r}"
    if (d / MANIFEST).is_file():
        try:
            run_id = json.loads((d / MANIFEST).read_text(encoding="utf-8")).get("run_id", "?")
        except (OSError, ValueError, AttributeError):
            run_id = "?"
        if not str(run_id).startswith("fit-"):
            return f"the results of the run {run_id!r} (cistrack run)"
    return ""


def check_fit_replacing(directory: str | Path, designation: str, where: str = "--out",
                        overwrite: bool = False) -> str:
    """Refuse (:class:`ConfigError` naming ``where`` and the directory) a fit of ``designation`` into
    ``directory`` when it holds a run's results or another object's fit, unless ``overwrite``.
    Returns what will be replaced (for a note when ``overwrite`` allowed it), or ""."""
    d = Path(directory)
    what = _earlier(d, designation) if d.is_dir() else ""
    if not what or overwrite:
        return what
    raise ConfigError(f"{where} {d}: holds {what}. A fit never replaces other results: give another --out, "
                      f"remove {d}, or add --overwrite to replace them")
