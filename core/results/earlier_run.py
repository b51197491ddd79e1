"""What a new run may replace in its results directory, checked before anything is computed.

``cistrack run`` replaces an earlier run of the same scenario, settings and seed in its results
directory (the same fingerprint, :mod:`cistrack.results.fingerprint`: running it again is how a
killed or changed run is redone), but never, unless told to (``--overwrite``), the results of
another scenario, other settings or another seed, nor a fit's (``cistrack fit``'s least-squares
results, even by a run of the fit's own ``scenario.toml``): :func:`check_replacing` refuses, naming the
directory, what is there and how the two differ. :func:`check_recording_path` refuses a
recording (``--rerun FILE``) that would be written over one of the run's own result files.
"""
from __future__ import annotations

import fnmatch
import json
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cistrack.errors import ConfigError
from cistrack.interfaces.reader import not_a_file
from cistrack.results.estimates import _PARTS as ESTIMATE_PARTS
from cistrack.results.estimates import ESTIMATES
from cistrack.results.fingerprint import scenario_fingerprint
from cistrack.results.output_paths import (EARLIER_RESULTS, FIT_LOCK, FIT_STARTED, RUN_LOCK, STUDY_LOCK,
                                           STUDY_RUNS_LOCK, check_printable_path, held_results)
from cistrack.results.store import MANIFEST, PARTS, STEPS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["check_replacing", "check_recording_path", "check_export_path", "RESULT_FILES", "RESULT_FOLDERS",
           "FIT_FILES", "FIT_PLOTS", "OptionWords", "CLI_WORDS", "PYTHON_WORDS", "clear_replaced_fit", "FIT_INPUTS"]

RESULT_FILES = (MANIFEST, STEPS, ESTIMATES, "scenario.toml", "scenario.json", RUN_LOCK)
"""The files a run writes in its results directory (and their temporary ``NAME.*`` files)."""
RESULT_FOLDERS = (PARTS, ESTIMATE_PARTS)
"""The folders of part files a run writes in its results directory."""
_SHOWN = 4
"""Differences named in a refusal (the rest are counted)."""


@dataclass(frozen=True)
class OptionWords:
    """How a refusal names its caller's options: ``cistrack run --out DIR --overwrite`` on the command
    line, ``ct.run(out=DIR, overwrite=True)`` from Python."""

    out: str = "--out"
    """The output option, as the refusal names it (``give another --out``)."""
    overwrite: str = "--overwrite"
    """The option that allows the replacement, as given (a note says it allowed one)."""
    add_overwrite: str = "add --overwrite"
    """What to do to allow it (``..., or add --overwrite to replace them``)."""


CLI_WORDS = OptionWords()
"""The command line's words."""
PYTHON_WORDS = OptionWords(out="out=", overwrite="overwrite=True", add_overwrite="pass overwrite=True")
"""The Python API's words (:func:`cistrack.run`, :func:`cistrack.fit`)."""


def _has_results(d: Path) -> bool:
    """Whether ``d`` holds a step table: merged, or the parts of a run that did not merge them."""
    return (d / STEPS).is_file() or any((d / PARTS).glob("part-*.parquet"))


def _flat(tables: Any, prefix: str = "") -> dict[str, Any]:
    """``{"filter": {"n_particles": 5}}`` -> ``{"filter.n_particles": 5}``."""
    if not isinstance(tables, dict):
        return {prefix: tables}
    out: dict[str, Any] = {}
    for key, value in tables.items():
        out.update(_flat(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def _recorded_tables(d: Path) -> dict | None:
    """The scenario tables an earlier run recorded (scenario.toml or .json), or None."""
    try:
        if (d / "scenario.toml").is_file():
            return tomllib.loads((d / "scenario.toml").read_text())
        if (d / "scenario.json").is_file():
            return json.loads((d / "scenario.json").read_text())
    except (OSError, ValueError):
        pass
    return None


def _differences(old: dict | None, new: dict) -> list[str]:
    """``key: there -> now`` for each scenario value that differs (``old`` None: none known)."""
    if old is None:
        return []
    a, b = _flat(old), _flat(json.loads(json.dumps(new, default=str)))
    keys = sorted(k for k in set(a) | set(b) if str(a.get(k, "-")) != str(b.get(k, "-")))
    return [f"{k}: {a.get(k, '(not set)')!r} there, {b.get(k, '(not set)')!r} now" for k in keys]


def _describe(man: dict, d: Path, scenario: Any, seed: int) -> str:
    """What the earlier run in ``d`` was and how this one differs, for a refusal."""
    status = str(man.get("status", "unknown"))
    there = (f"{'an' if status[:1] in 'aeiou' else 'a'} {status} run of scenario '{man.get('scenario', '?')}', seed "
             f"{man.get('seed', '?')}, filter {_component(man, 'filter')}, IOD {_component(man, 'iod')}")
    diffs = _differences(_recorded_tables(d), getattr(scenario, "raw", {}) or {})
    if man.get("seed") != int(seed):
        diffs.insert(0, f"seed: {man.get('seed')!r} there, {int(seed)} now")
    if not diffs:
        diffs = ["its scenario, seed or measurement file (the fingerprint differs)"]
    more = f" and {len(diffs) - _SHOWN} more" if len(diffs) > _SHOWN else ""
    return f"{there}; this run differs in " + "; ".join(diffs[:_SHOWN]) + more


def _component(man: dict, kind: str) -> str:
    comp = (man.get("components") or {}).get(kind)
    return str(comp.get("name", "?")) if isinstance(comp, dict) else "?"


def check_replacing(directory: str | Path, scenario: Any, seed: int, where: str = "--out",
                    overwrite: bool = False, words: OptionWords = CLI_WORDS) -> str:
    """Refuse (:class:`ConfigError` naming ``where`` and the directory) a run of ``scenario`` and
    ``seed`` in ``directory`` that holds the step table of a run with another fingerprint (or an
    unreadable manifest), or a fit's results (its ``fit.json``, whatever the fingerprint of its
    filter run), unless ``overwrite``. Returns a description of the results that will be
    replaced (for a note when ``overwrite`` allowed it), or "" when nothing of another run is there.
    ``words``: the caller's options, as the refusal names them (:data:`CLI_WORDS`, :data:`PYTHON_WORDS`)."""
    d = Path(directory)
    fit = _fit_there(d)
    if fit:
        return _replacing_a_fit(d, fit, where, overwrite, words)
    if not (d / MANIFEST).is_file() or not _has_results(d):
        return ""
    try:
        man = json.loads((d / MANIFEST).read_text())
        if not isinstance(man, dict):
            raise ValueError("not a JSON object")
    except (OSError, ValueError) as exc:
        man, what = None, f"the results of a run whose {MANIFEST} cannot be read ({exc})"
    if man is not None:
        if man.get("fingerprint") == scenario_fingerprint(scenario, seed):
            return ""  # the same run again: it replaces its own results
        what = _describe(man, d, scenario, seed)
    if overwrite:
        return what
    raise ConfigError(f"{where} {d}: holds {what}. A run never replaces the results of another scenario, "
                      f"other settings or another seed: give another {words.out}, remove {d}, or "
                      f"{words.add_overwrite} to replace them")


def _fit_there(d: Path) -> str:
    """The fit ``d`` holds (its ``fit.json``), in words for a refusal, or "" when it holds none."""
    if not (d / "fit.json").is_file():
        return ""
    return held_results(d) or "a fit record (fit.json) that cannot be read"


def _replacing_a_fit(d: Path, fit: str, where: str, overwrite: bool, words: OptionWords) -> str:
    """Refuse a run into the folder of a fit unless ``overwrite``; else return what it replaces.
    The fit's filter run has the fingerprint of the fit's own scenario.toml, but a run of it is
    not the fit again: it would remove the least-squares results (fit.json, residuals, plots)."""
    what = f"{fit}, the least-squares orbit of cistrack fit with its filter run"
    if overwrite:
        return what
    raise ConfigError(f"{where} {d}: holds {what}. A run never replaces a fit's results, not even a run of the "
                      f"fit's own scenario.toml: give another {words.out}, remove {d}, or {words.add_overwrite} "
                      "to replace them")


def check_recording_path(recording: str | Path, directory: str | Path, where: str = "--rerun") -> None:
    """Refuse (:class:`ConfigError` naming both paths) a recording path that is the results
    directory, one of the run's result files (or their temporary files), a file a run removes as it
    starts (:data:`~cistrack.results.output_paths.EARLIER_RESULTS`), or a path inside its part
    folders: writing the recording there would replace the run's results, or the run the recording.
    A path the system refuses (too long a name, ...) is refused too, before the run starts."""
    try:
        _check_recording_path(recording, directory, where)
    except OSError as exc:
        raise ConfigError(f"{where} {recording}: cannot write there ({exc.strerror or exc})") from None


def _check_recording_path(recording: str | Path, directory: str | Path, where: str) -> None:
    r, d = Path(os.path.abspath(recording)).resolve(), Path(os.path.abspath(directory)).resolve()
    why = ""
    if r != d and (str(recording).endswith(("/", os.sep)) or r.is_dir()):
        raise ConfigError(f"{where} {recording}: a directory; give the recording's file name (e.g. "
                          f"{Path(recording) / 'run.rrd'})")
    if r == d:
        why = f"is the results directory {directory} itself"
    elif _in_part_folders(r, d):
        why = f"is inside a folder of part files of the results directory {directory}"
    elif _named_as(r, d, RESULT_FILES):
        why = f"is one of the run's own result files in the results directory {directory}"
    elif r.parent == d and any(fnmatch.fnmatch(r.name, p) for p in EARLIER_RESULTS):
        why = (f"is a file that the run removes as it starts in the results directory {directory} "
               "(an earlier run's export or fit file)")
    elif r.exists() and any(_same(r, d / n) for n in RESULT_FILES):
        why = f"is the same file as one of the run's result files in the results directory {directory}"
    if why:
        raise ConfigError(f"{where} {recording}: {why}; the recording would replace the run's results. Give a "
                          f"recording path outside {Path(directory) / PARTS} and {Path(directory) / ESTIMATE_PARTS}, "
                          f"not named like a result file (e.g. {Path(directory) / 'recording.rrd'})")
    special = not_a_file(recording) if os.path.lexists(recording) and not r.is_dir() else None
    if special is not None and special.startswith("is not a regular file"):  # opening a pipe to write waits for a reader
        raise ConfigError(f"{where} {recording}: {special}, which a recording is never written to; give the path of a "
                          "file (e.g. run.rrd)")
    _check_recording_name(recording, r, directory, where)
    _check_writable(Path(recording))


def _check_recording_name(recording: str | Path, r: Path, directory: str | Path, where: str) -> None:
    """Refuse a recording path that does not end in .rrd, or an existing file that is not a recording."""
    if not str(recording).lower().endswith(".rrd"):
        raise ConfigError(f"{where} {recording}: a recording's file name ends in .rrd (cistrack view and the rerun "
                          f"viewer read it by that name); e.g. {Path(directory) / 'recording.rrd'}"
                          + (" (standard output is not supported)" if str(recording) == "-" else ""))
    if r.is_file() and not _recording_or_empty(r):
        raise ConfigError(f"{where} {recording}: exists and is not a rerun recording; --overwrite replaces results "
                          "and recordings, never another file: give a new file name ending in .rrd")


def _recording_or_empty(path: Path) -> bool:
    """Whether ``path`` starts with rerun's recording header (``RRF``) or is empty."""
    try:
        with open(path, "rb") as fh:
            return fh.read(3) in (b"", b"RRF")
    except OSError:
        return False


CONTROL_FILES = (RUN_LOCK, FIT_LOCK, FIT_STARTED, STUDY_LOCK, STUDY_RUNS_LOCK)
"""The lock and start-marker files of results folders: never an export's or a prediction's output."""

FIT_FILES = ("fit.json", "residuals.csv", "lov.csv", "observations.psv", "observations-early.psv")
"""A fit's own records in its results directory (beside the run's)."""
FIT_PLOTS = ("residuals-*.png", "residuals-*.svg")
"""A fit's residual plots in its results directory (one per site)."""


FIT_INPUTS = ("observations.psv", "observations.tdm", "observations-early.psv", "observations-early.tdm")
"""The merged observation files a ``cistrack fit`` writes into its directory before its records."""


def clear_replaced_fit(directory: str | Path) -> list[Path]:
    """Remove what a ``cistrack fit`` leaves in ``directory`` beside its filter run's results (its
    merged observation files :data:`FIT_INPUTS`, its start marker, and the ``arc-YYYY-MM-DD``
    folders of a fit of each arc, those holding nothing but what such a fit writes), for a run
    that replaces it (``--overwrite``): they would describe another orbit beside the run's results.
    Nothing else is removed, and nothing from a directory no fit wrote; returns the paths removed."""
    import shutil

    from cistrack.results.output_paths import FIT_STARTED

    d = Path(directory)
    if not ((d / "fit.json").is_file() or (d / FIT_STARTED).is_file()):
        return []
    gone = [d / n for n in FIT_INPUTS + (FIT_STARTED,) if (d / n).is_file() and not (d / n).is_symlink()]
    for p in gone:
        p.unlink()
    arcs = [p for p in sorted(d.glob("arc-*")) if _a_fits_arc_folder(p)]
    for p in arcs:
        shutil.rmtree(p)
    return gone + arcs


def _a_fits_arc_folder(p: Path) -> bool:
    """Whether ``p`` is an ``arc-YYYY-MM-DD`` folder of a fit of each arc: a real folder holding a
    cistrack fit record and nothing a fit does not write (a user's own file there keeps it)."""
    import re

    from cistrack.results.output_paths import EARLIER_RESULTS, FIT_LOCK, RUN_LOCK

    if not re.fullmatch(r"arc-\d{4}-\d{2}-\d{2}", p.name) or p.is_symlink() or not p.is_dir():
        return False
    if not _is_fit_record(p / "fit.json"):
        return False
    ours = set(RESULT_FILES + RESULT_FOLDERS + FIT_INPUTS) | {FIT_LOCK, RUN_LOCK, ".fit-started"}
    return all(e.name in ours or any(fnmatch.fnmatch(e.name, g) for g in EARLIER_RESULTS) for e in p.iterdir())


def _is_fit_record(path: Path) -> bool:
    try:
        return json.loads(path.read_text(encoding="utf-8")).get("format") == "cistrack-fit"
    except (OSError, ValueError, AttributeError):
        return False


def _in_part_folders(path: Path, d: Path) -> bool:
    """Whether ``path`` lies inside one of the part folders of the results directory ``d``."""
    return any(path.is_relative_to(d / f) for f in RESULT_FOLDERS)


def _named_as(path: Path, d: Path, names: tuple[str, ...]) -> bool:
    """Whether ``path`` is one of ``names`` in ``d``, or one of their temporary files (``NAME.*``)."""
    return path.parent == d and any(path.name == n or path.name.startswith(n + ".") for n in names)


def check_export_path(out: str | Path, directory: str | Path, where: str = "--out", *, by: str = "the export",
                      instead: str = "give another file (default {directory}/estimate.<format>)",
                      overwrite: bool = False) -> None:
    """Refuse (:class:`ConfigError` naming ``where``) a file written from ``directory`` (by an
    export, or ``by`` another writer such as a sky prediction) that is one of the results it is
    made from: the run's files (``manifest.json``, ``steps.parquet``, ...), a fit's records and
    residual plots, or a path inside the part folders of ``directory``; and, unless
    ``overwrite``, one in the folder of other cistrack results (another run, fit or study:
    :func:`~cistrack.results.output_paths.held_results`), where it would be taken for theirs.
    ``instead``: what to do, said in the refusal (``{directory}`` is replaced by the directory)."""
    check_printable_path(out, where)
    o, d = Path(os.path.abspath(out)).resolve(), Path(os.path.abspath(directory)).resolve()
    plot = o.parent == d and any(fnmatch.fnmatch(o.name, p) for p in FIT_PLOTS)
    if o == d or plot or _named_as(o, d, RESULT_FILES + FIT_FILES) or _in_part_folders(o, d):
        raise ConfigError(f"{where} {out}: is one of the results of {directory} (or among them); {by} would "
                          f"replace them: " + instead.format(directory=Path(directory)))
    if o.name in CONTROL_FILES:
        raise ConfigError(f"{where} {out}: is the name of a file cistrack keeps in a results folder to know who "
                          f"writes there ({', '.join(CONTROL_FILES)}); {by} would replace a running process's lock: "
                          + instead.format(directory=Path(directory)))
    holder = o.parent
    theirs = o.name in RESULT_FILES + FIT_FILES or any(fnmatch.fnmatch(o.name, p) for p in FIT_PLOTS)
    if holder != d and theirs and any((holder / n).is_file() for n in ("fit.json", MANIFEST)):
        raise ConfigError(f"{where} {out}: is one of the results of {holder}; {by} would replace them: "
                          + instead.format(directory=Path(directory)))
    other = "" if overwrite or holder == d else held_results(holder)
    if other:
        raise ConfigError(f"{where} {out}: its folder {holder} holds {other}, not those of {directory}; {by} "
                          f"written there would be taken for one of theirs: {instead.format(directory=Path(directory))}, "
                          "or add --overwrite to write it there all the same")


def _check_writable(recording: Path) -> None:
    """Refuse, before the run starts, a recording path the system will not let us write (tried:
    an existing file opened to append, a new one created and removed again, a temporary file in
    a folder given for one file per run; a link is never written through). A missing folder is
    left to the results directory (made later) or the recorder, which names it. An OSError here
    is the refusal (:func:`check_recording_path` says it)."""
    if recording.is_dir():
        with tempfile.TemporaryFile(dir=recording):
            pass
    elif recording.is_symlink():
        return  # never written through here: the recorder refuses what is there without --overwrite
    elif os.path.lexists(recording):
        with open(recording, "ab"):
            pass
    elif recording.parent.is_dir():
        with open(recording, "xb"):  # created here, only here, and removed again
            pass
        recording.unlink()


def _same(a: Path, b: Path) -> bool:
    try:
        return b.exists() and os.path.samefile(a, b)
    except OSError:
        return False
