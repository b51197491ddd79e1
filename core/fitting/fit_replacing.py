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
from cistrack.results.earlier_run import CLI_WORDS, OptionWords
from cistrack.results.store import MANIFEST

__all__ = ["check_fit_replacing", "check_fit_form", "check_several_objects_dir", "other_form_results", "remove_other_form",
           "FIT_RECORD"]

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
                        overwrite: bool = False, words: OptionWords = CLI_WORDS) -> str:
    """Refuse (:class:`ConfigError` naming ``where`` and the directory) a fit of ``designation`` into
    ``directory`` when it holds a run's results or another object's fit, unless ``overwrite``.
    Returns what will be replaced (for a note when ``overwrite`` allowed it), or "". ``words``: the
    caller's options, as the refusal names them."""
    d = Path(directory)
    what = _earlier(d, designation) if d.is_dir() else ""
    if not what or overwrite:
        return what
    raise ConfigError(f"{where} {d}: holds {what}. A fit never replaces other results: give another {words.out}, "
                      f"remove {d}, or {words.add_overwrite} to replace them")


def other_form_results(directory: str | Path, each: bool) -> list[Path]:
    """What an earlier fit of the other ``fit.arcs`` form left in ``directory``: for a fit of each
    arc (``each``), the top-level fit.json of a whole-arc fit; otherwise the ``arc-*`` folders of a
    fit of each arc. A refit of the other form would leave them beside its own results."""
    d = Path(directory)
    if not d.is_dir():
        return []
    if each:
        return [d / FIT_RECORD] if (d / FIT_RECORD).is_file() else []
    return sorted(p for p in d.glob("arc-*") if p.is_dir() and (p / FIT_RECORD).is_file())


def check_fit_form(directory: str | Path, each: bool, where: str = "--out", overwrite: bool = False,
                   words: OptionWords = CLI_WORDS) -> list[Path]:
    """Refuse (:class:`ConfigError`) a fit into ``directory`` that holds an earlier fit of the other
    ``fit.arcs`` form (:func:`other_form_results`), unless ``overwrite``: then returns what to remove."""
    stale = other_form_results(directory, each)
    if not stale or overwrite:
        return stale
    what = (f"the fit of the whole arc ({FIT_RECORD})" if each else
            f"{len(stale)} folder(s) of a fit of each arc ({', '.join(p.name for p in stale[:3])}"
            + (", ..." if len(stale) > 3 else "") + ")")
    raise ConfigError(f"{where} {directory}: holds {what} from an earlier fit with another fit.arcs; this fit would "
                      f"leave it beside its own results: give another {words.out}, remove it, or {words.add_overwrite} "
                      "to remove it")


def check_several_objects_dir(directory: str | Path, where: str = "--out", overwrite: bool = False,
                              words: OptionWords = CLI_WORDS) -> list[Path]:
    """Refuse (:class:`ConfigError`) a fit of several objects into ``directory`` (each object into its
    ``fit-<designation>`` folder there) when ``directory`` holds a fit of one object (a top-level
    fit.json), unless ``overwrite``: then returns it, to remove with :func:`remove_other_form`. Left
    beside the new folders, that stale fit had been what export and predict of ``directory`` read."""
    d = Path(directory)
    stale = [d / FIT_RECORD] if (d / FIT_RECORD).is_file() else []
    if not stale or overwrite:
        return stale
    raise ConfigError(f"{where} {d}: holds the fit of one object ({FIT_RECORD}); this fit of several objects writes "
                      f"a folder for each (fit-<designation>) and would leave it beside them, where export and "
                      f"predict of {d} would still read it: give another {words.out}, remove it, or "
                      f"{words.add_overwrite} to remove it")


def remove_other_form(directory: str | Path, stale: list[Path]) -> None:
    """Remove what :func:`check_fit_form` returned: ``arc-*`` folders, or a whole-arc fit's files."""
    import shutil

    from cistrack.results.earlier_run import FIT_FILES, RESULT_FILES, RESULT_FOLDERS
    from cistrack.results.output_paths import clear_earlier_results

    d = Path(directory)
    for p in stale:
        if p.is_dir():
            shutil.rmtree(p)
        elif p.name == FIT_RECORD:  # the whole-arc fit: its record, plots, observations and filter run
            clear_earlier_results(d)
            for name in RESULT_FILES + FIT_FILES:
                (d / name).unlink(missing_ok=True)
            for name in RESULT_FOLDERS:
                shutil.rmtree(d / name, ignore_errors=True)
