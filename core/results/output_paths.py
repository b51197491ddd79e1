"""Where results may be written: checked before anything is computed.

A results directory is either new, empty, or an earlier cistrack results directory (it holds a
``manifest.json`` that cistrack wrote: a JSON object with the run's ``run_id`` and the
``versions`` it ran with, ``cistrack``'s among them; a web app's ``manifest.json`` is not one);
anything else is refused, so that starting a run never deletes or replaces
files that cistrack did not write. A directory in which a run failed before it wrote its manifest
(a full disk) counts as empty: it holds only the run's lock file and part folders (``steps/``,
``estimates-parts/``) with nothing in them but part files, so the retry runs there. The directory
is created here, so an unwritable place fails at once with the reason, not after the run has
computed every step.

A study directory (:func:`check_study_dir`) follows the same rule with a study's record in place of
a run's manifest: new, empty, or an earlier directory of the same study (its ``study.json`` names
it); never the root of the file system, a single run's results directory or a file.
"""
from __future__ import annotations

import fnmatch
import hashlib
import json
import os
from collections import Counter
from collections.abc import Callable, Iterable
from pathlib import Path

from cistrack.errors import ConfigError

__all__ = ["check_output_dir", "check_study_dir", "held_results", "recorded_study", "is_same_study", "check_writable_dir", "make_writable_dir", "clear_earlier_results", "EARLIER_RESULTS",
           "STUDY_RECORD", "STUDY_LOCK", "STUDY_RUNS_LOCK", "RUN_LOCK", "FIT_LOCK", "FIT_STARTED", "PART_FOLDERS", "distinct_stems",
           "fit_folders_inside"]

EARLIER_RESULTS = ("estimate.*", "fit.json", "residuals.csv", "residuals-*.png", "residuals-*.svg", "lov.csv",
                   "sky-*.csv", "sky-*.png", "residuals.svg")
"""Files that describe an earlier run or fit of a results directory and that a new run there does
not itself replace: its exports (``cistrack export``'s default ``estimate.<format>``), its sky
predictions (``cistrack predict``'s default ``sky-<CODE>.csv`` and ``.png``), a filter run's
residual figure (drawn again at the end of a run that draws one; a fit's run does not) and a
fit's record, residuals, residual plots and line of variations. A run that starts in the directory
removes them (:func:`clear_earlier_results`), so that an export or a check never mixes the new
run with the old one's files (the fit's own files are written again when its fit ends)."""

STUDY_RECORD = "study.json"
"""The record a study directory holds (written by ``cistrack study run``)."""
STUDY_LOCK = ".study.lock"
"""The lock file of a study directory (see :mod:`cistrack.studies.study_lock`); not content."""
STUDY_RUNS_LOCK = ".study-runs.lock"
"""The lock file its runs share while they write (see :mod:`cistrack.studies.study_lock`); not content."""
RUN_LOCK = ".run.lock"
FIT_LOCK = ".fit.lock"
"""Held by a whole ``cistrack fit`` of a directory (its filter run holds :data:`RUN_LOCK` inside it)."""
FIT_STARTED = ".fit-started"
"""Written into a fit's directory before anything else of the fit: with it, the merged observation
files a fit stopped before its records (``observations*.psv``/``.tdm``) are the fit's own and a
retry may replace them."""
"""The lock file of a results directory that ``cistrack run`` holds while it writes there (see
:mod:`cistrack.results.dir_lock`); not content."""
PART_FOLDERS = ("steps", "estimates-parts")
"""The folders of part files a run writes while it runs (``steps/``, ``estimates-parts/``)."""


def check_output_dir(directory: str | Path, where: str, records: tuple[str, ...] = ("manifest.json",)) -> Path:
    """Create ``directory`` (parents included) or check that it may hold results; return it.

    ``records``: the files that mark a directory as cistrack's results (a run's ``manifest.json``;
    a fit adds its ``fit.json``, which a fit that stopped before its filter run writes alone).
    Raises :class:`ConfigError` naming ``where`` (a flag or key) if it exists and is not a
    directory, is a non-empty directory holding none of ``records``, or cannot be created or
    written."""
    d = Path(directory)
    try:  # a parent that may not be searched (EACCES) answers here, not with a traceback
        if d.exists() and not d.is_dir():
            raise ConfigError(f"{where} {d}: exists and is not a directory; give a new directory or an "
                              "earlier results directory")
        owner = _run_owning_parts_of(d)
        if owner is not None:
            raise ConfigError(f"{where} {d}: lies inside the part folders of the run in {owner}, which its "
                              "merges and --overwrite replace; give a directory outside that run")
        if d.is_dir() and not any(_is_cistrack_record(d / name) for name in records) and not _holds_no_results(d):
            raise ConfigError(f"{where} {d}: is not empty and holds no cistrack {' or '.join(records)}; results "
                              "go to a new or empty directory, or replace an earlier run's results directory"
                              + _several_fits_hint(d, where))
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot look there ({exc.strerror or exc})") from None
    return _create_writable(d, where)


def fit_folders_inside(d: str | Path, pattern: str) -> list[str]:
    """The names, sorted, of ``d``'s folders matching ``pattern`` (``fit-*``: one per object;
    ``arc-*``: one per arc of ``fit.arcs=each``) that hold a fit record cistrack wrote."""
    return sorted(p.name for p in Path(d).glob(pattern) if _is_cistrack_record(p / "fit.json"))


def _several_fits_hint(d: Path, where: str) -> str:
    """What to give instead when ``d`` holds the fits of several objects (``fit-<designation>``
    folders, each with its fit.json), "" otherwise."""
    fits = fit_folders_inside(d, "fit-*")
    if not fits:
        return ""
    shown = ", ".join(fits[:4]) + (f" and {len(fits) - 4} more" if len(fits) > 4 else "")
    return (f" (it holds the fits of several objects, one folder each: {shown}; to fit one of them again, give "
            f"{where} {d}/fit-<designation>, e.g. {d / fits[0]}, or the same files as before with {where} {d})")


def _run_owning_parts_of(d: Path) -> Path | None:
    """The results directory of a cistrack run whose part folders (:data:`PART_FOLDERS`) hold ``d``,
    or None."""
    for parent in Path(os.path.abspath(d)).parents:
        if parent.name in PART_FOLDERS and _is_cistrack_record(parent.parent / "manifest.json"):
            return parent.parent
    return None


def _is_cistrack_record(path: Path) -> bool:
    """Whether ``path`` is a record cistrack wrote: a run's manifest (a JSON object with a ``run_id``
    and ``versions`` naming cistrack) or a fit's record (``"format": "cistrack-fit"``)."""
    return _cistrack_record(path) is not None


def _cistrack_record(path: Path) -> dict | None:
    """The record of :func:`_is_cistrack_record` at ``path``, or None when it is not one."""
    try:
        data = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict):
        return None
    versions = data.get("versions")
    ours = data.get("format") == "cistrack-fit" or (isinstance(data.get("run_id"), str) and isinstance(versions, dict)
                                                    and "cistrack" in versions)
    return data if ours else None


def held_results(directory: str | Path) -> str:
    """What cistrack results the folder ``directory`` holds, in words for a message ("" when none
    or not a folder): a fit (its ``fit.json``), a run (its ``manifest.json``) or a study (its
    ``study.json``)."""
    d = Path(directory)
    fit, run = _cistrack_record(d / "fit.json"), _cistrack_record(d / "manifest.json")
    if fit is not None:
        return f"the fit of {fit.get('designation')!r} (fit.json)"
    if run is not None:
        return f"the results of the run {run.get('run_id')!r} (manifest.json)"
    try:
        return f"the study {recorded_study(d / STUDY_RECORD)[0]!r} ({STUDY_RECORD})"
    except (OSError, ValueError):
        return ""


def _holds_no_results(d: Path) -> bool:
    """Whether ``d`` (a directory without a manifest) holds nothing but what a run that failed before
    it wrote its manifest leaves (a full disk): its lock file and part folders that hold only part
    files, temporary part files, or nothing. Such a directory is a run's own, with no results a
    new run should protect; the new run replaces its parts."""
    started = (d / FIT_STARTED).is_file()
    for e in d.iterdir():
        if e.name in (RUN_LOCK, FIT_LOCK) or (started and _is_fit_input(e)):
            continue
        if e.name not in PART_FOLDERS or e.is_symlink() or not e.is_dir():
            return False
        if any(not (p.is_file() and fnmatch.fnmatch(p.name, "part-*.*") and p.suffix in (".parquet", ".tmp"))
               for p in e.iterdir()):
            return False
    return True


def _is_fit_input(e: Path) -> bool:
    """The fit's marker or one of the merged observation files a fit writes before its records."""
    return e.is_file() and not e.is_symlink() and (
        e.name == FIT_STARTED or (fnmatch.fnmatch(e.name, "observations*.*") and e.suffix in (".psv", ".tdm")))


def clear_earlier_results(directory: str | Path) -> list[Path]:
    """Remove the :data:`EARLIER_RESULTS` files of ``directory`` (a results directory a run is
    starting in); returns the paths removed."""
    d = Path(directory)
    gone = []
    for pattern in EARLIER_RESULTS:
        for path in sorted(d.glob(pattern)):
            if path.is_file() or path.is_symlink():
                path.unlink()
                gone.append(path)
    return gone


def check_writable_dir(directory: str | Path, where: str) -> Path:
    """Create ``directory`` (parents included) if needed and check that files can be made there
    (a folder for files of cistrack's own names, e.g. ``study run --rerun DIR``); return it.
    Raises :class:`ConfigError` naming ``where`` for a file, or a place that cannot be written."""
    d = Path(directory)
    try:
        if d.exists() and not d.is_dir():
            raise ConfigError(f"{where} {d}: exists and is not a directory; give a directory")
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot look there ({exc.strerror or exc})") from None
    return _create_writable(d, where)


def make_writable_dir(d: Path) -> None:
    """Create ``d`` (parents included) and make and remove a file there; OSError when either fails."""
    d.mkdir(parents=True, exist_ok=True)
    probe = d / ".cistrack-write-test"
    probe.write_bytes(b"")
    probe.unlink()


def _create_writable(d: Path, where: str) -> Path:
    """Create ``d`` (parents included) and check that a file can be made there."""
    try:
        str(d).encode("utf-8")
    except UnicodeEncodeError:
        raise ConfigError(f"{where} {str(d)!r}: the path is not valid UTF-8 (bytes no character has), which the "
                          "results' own records cannot hold; give a name in UTF-8") from None
    check_printable_path(d, where)
    _check_path_room(d, where)
    if d.is_symlink() and not d.exists():
        target = os.readlink(d)
        if os.path.lexists(d.parent / target):
            raise ConfigError(f"{where} {d}: a loop of symbolic links (through {target}); give a directory")
        raise ConfigError(f"{where} {d}: a link to {target}, which does not exist; give a directory, or create "
                          "the link's target first")
    try:
        make_writable_dir(d)
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot write there ({exc.strerror or exc})") from None
    return d


def check_printable_path(d: str | Path, where: str) -> None:
    """ConfigError for a path holding a control character (a newline, tab, escape...): legal for
    the system, but every message, log line and record naming the results would show it broken
    (a newline in --out had been taken, and the run's lines split in two)."""
    text = str(d)
    bad = next((i for i, ch in enumerate(text) if ord(ch) < 32 or ord(ch) == 127), None)
    if bad is not None:
        raise ConfigError(f"{where} {text!r}: the path holds a control character ({text[bad]!r} at position {bad}), "
                          "which messages and records naming it would show broken; give a name without one")


INSIDE_PATH_BYTES = 64
"""Room kept for the longest path a results directory writes inside itself (``steps/`` parts,
``.manifest.json.<hex>.tmp`` and the like, under 40 bytes)."""


def _check_path_room(d: Path, where: str) -> None:
    """ConfigError when the files a results directory holds would pass the system's limit on a
    path's length: a 4,070-byte --out had been made, the run's IOD done, and its first record
    then refused by the system (a half-made directory left behind)."""
    full = os.fsencode(os.path.abspath(d))
    existing = Path(os.path.abspath(d))
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    try:
        limit = os.pathconf(existing, "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):
        limit = 4096
    if len(full) + INSIDE_PATH_BYTES > limit:
        raise ConfigError(f"{where} {str(d)[:60]}...: the path is {len(full)} bytes long, and the results' own files "
                          f"inside it would pass the system's limit of {limit} bytes a path; give a shorter path")


def recorded_study(record: Path) -> tuple[str | None, str | None]:
    """(name, source) of the study a ``study.json`` records; raises OSError or ValueError when it
    cannot be read."""
    data = json.loads(record.read_text())
    if not isinstance(data, dict):
        raise ValueError("not a JSON object")
    name, source = data.get("name"), data.get("source")
    return (str(name) if name is not None else None), (str(source) if source is not None else None)


def is_same_study(recorded: tuple[str | None, str | None], name: str, source: str) -> bool:
    """Whether the study a ``study.json`` records (:func:`recorded_study`: name, source) is study
    ``name`` from the file ``source`` (by name; by source for a record written before names were)."""
    rec_name, rec_source = recorded
    return rec_name == name if rec_name is not None else rec_source == source


def single_results(d: Path) -> str:
    """What ``d`` holds when it is one run's or one fit's results folder, in words (``the results
    of a single run (manifest.json)``, ``a fit's results (fit.json)``); "" otherwise."""
    if (d / "fit.json").is_file():
        return "a fit's results (fit.json)"
    return "the results of a single run (manifest.json)" if (d / "manifest.json").is_file() else ""


def check_study_dir(directory: str | Path, name: str, source: str, where: str) -> Path:
    """Create the study directory ``directory`` or check that study ``name`` (from the study file
    ``source``) may write there; return it.

    Allowed: a new or empty directory, or an earlier directory of the same study (its
    ``study.json`` records ``name``, or, written before it recorded names, ``source``). Raises
    :class:`ConfigError` naming ``where`` (``--out`` or "the study directory") for the root of
    the file system, a file, a single run's results directory, another study's directory, any
    other non-empty directory, and a place that cannot be created or written."""
    d = Path(directory)
    allowed = ("give a new or empty directory, or the directory of an earlier run of the same study")
    try:
        if d.resolve() == Path(d.resolve().anchor):
            raise ConfigError(f"{where} {d}: the root of the file system; {allowed}")
        if d.exists() and not d.is_dir():
            raise ConfigError(f"{where} {d}: exists and is not a directory; {allowed}")
        if d.is_dir():
            record = d / STUDY_RECORD
            if single_results(d):
                raise ConfigError(f"{where} {d}: holds {single_results(d)}, not a study; {allowed}")
            if record.is_file():
                try:
                    rec_name, rec_source = recorded_study(record)
                except (OSError, ValueError) as exc:
                    raise ConfigError(f"{where} {d}: its {STUDY_RECORD} cannot be read ({exc}); {allowed} "
                                      f"(or delete that {STUDY_RECORD} if the directory is this study's)") from None
                if not is_same_study((rec_name, rec_source), name, source):
                    raise ConfigError(f"{where} {d}: holds another study ("
                                      + (f"'{rec_name}'" if rec_name is not None else f"from {rec_source}")
                                      + f"), not '{name}'; {allowed}")
            elif any(e.name not in (STUDY_LOCK, STUDY_RUNS_LOCK) for e in d.iterdir()):
                raise ConfigError(f"{where} {d}: is not empty and holds no {STUDY_RECORD} of a cistrack "
                                  f"study; {allowed}")
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot look there ({exc.strerror or exc})") from None
    return _create_writable(d, where)


def distinct_stems(keys: Iterable[str], stem: Callable[[str], str]) -> dict[str, str]:
    """``stem(key)`` for each key, as file or directory names that never coincide: keys whose stems
    coincide (letter case counts as the same, as on a case-insensitive file system) each get a
    short hash of the key appended."""
    stems = {key: stem(key) for key in dict.fromkeys(keys)}
    counts = Counter(s.casefold() for s in stems.values())
    return {key: s if counts[s.casefold()] == 1 else f"{s}-{hashlib.sha256(key.encode('utf-8')).hexdigest()[:8]}"
            for key, s in stems.items()}

