"""What a fit may replace in its results directory, checked before anything is computed.

``cistrack fit`` redoes an earlier fit of the same object in its directory (the way to refit after
new observations or other settings), but never, unless told to (``--overwrite``), the results of a
``cistrack run``, a fit of another object, or a fit of the same designation that shares no
observation with this one (another object under a reused ``trkSub``): :func:`check_fit_replacing`
refuses, naming the directory and what is there.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, ConfigError
from cistrack.results.earlier_run import CLI_WORDS, OptionWords
from cistrack.results.store import MANIFEST

__all__ = ["check_fit_replacing", "check_fit_form", "check_several_objects_dir", "other_form_results", "remove_other_form",
           "FIT_RECORD"]

FIT_RECORD = "fit.json"
"""The record a finished fit writes last in its directory."""


def _earlier(d: Path, designation: str, observed: tuple[str, np.ndarray] | None = None) -> str:
    """What ``d`` holds that a fit of ``designation`` (``observed``: see :func:`check_fit_replacing`)
    must not replace, or ""
    (nothing, or a fit of it that shares an observation with it: :func:`_other_observations`)."""
    record = d / FIT_RECORD
    if record.is_file():
        try:
            earlier = json.loads(record.read_text(encoding="utf-8"))
            name = earlier.get("designation")
        except (OSError, ValueError, AttributeError) as exc:
            return f"a fit record that cannot be read ({exc})"
        if name != designation:
            return f"the fit of another object, {name!r}"
        return _other_observations(d, earlier, observed)
    if (d / MANIFEST).is_file():
        try:
            run_id = json.loads((d / MANIFEST).read_text(encoding="utf-8")).get("run_id", "?")
        except (OSError, ValueError, AttributeError):
            run_id = "?"
        if not str(run_id).startswith("fit-"):
            return f"the results of the run {run_id!r} (cistrack run)"
    return ""


def _other_observations(d: Path, record: dict, observed: tuple[str, np.ndarray] | None) -> str:
    """"" when the earlier fit of the same designation in ``d`` (its ``record``, and its copy of the
    observations there) shares an observation time (within 1 ms) with ``observed`` (UTC epoch,
    times TU since it), or when either is unknown: a refit. A
    fit sharing none is of other observations (a ``trkSub`` is assigned locally and reused: two
    objects, two seasons, had replaced each other silently, probe N6); said with its files and dates."""
    from cistrack.runs.observation_files import read_observations

    copies = [p for p in (d / "observations.psv", d / "observations.tdm") if p.is_file()]
    if observed is None or not copies:
        return ""
    epoch, times = observed
    try:
        old = np.sort(np.asarray(read_observations(copies[0], epoch).times, dtype=float))
    except CistrackError:
        return ""
    new = np.asarray(times, dtype=float)
    k = np.clip(np.searchsorted(old, new), 1, max(old.size - 1, 1))
    near = np.minimum(np.abs(new - old[k - 1]), np.abs(new - old[np.minimum(k, old.size - 1)]))
    if old.size == 0 or np.any(near <= 1e-3 / units.TU_S):
        return ""
    arc = record.get("arc") or {}
    files = ", ".join(str(f) for f in record.get("files") or []) or "its files"
    return (f"an earlier fit of {record.get('designation')!r} of other observations ({files}: {old.size} observations "
            f"from {str(arc.get('first_utc', '?'))[:10]} to {str(arc.get('last_utc', '?'))[:10]}, none of them "
            "among this fit's; another object under the same designation?)")


def check_fit_replacing(directory: str | Path, designation: str, where: str = "--out",
                        overwrite: bool = False, words: OptionWords = CLI_WORDS,
                        observed: tuple[str, np.ndarray] | None = None) -> str:
    """Refuse (:class:`ConfigError` naming ``where`` and the directory) a fit of ``designation`` into
    ``directory`` when it holds a run's results, another object's fit, or a fit of the same
    designation that shares no observation with this one (``observed``: the UTC epoch and this
    fit's observation times (K,), TU since it; None: not checked), unless ``overwrite``. Returns what will be replaced (for
    a note when ``overwrite`` allowed it), or "". ``words``: the caller's options, as the refusal
    names them."""
    d = Path(directory)
    what = _earlier(d, designation, observed) if d.is_dir() else ""
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
