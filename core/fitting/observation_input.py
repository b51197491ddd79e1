"""Observation files in, one measurement set per object out: what ``cistrack fit`` reads.

Each file is read by the registered reader its name's suffix names (``.psv``, ``.xml``, ``.tdm``,
...); a file whose suffix no reader claims is offered to every registered reader in turn and taken by the
first that reads it. A file naming several objects (ADES permID / provID / artSat / trkSub, the MPC 80-column
designation, TDM ``PARTICIPANT_2``) is read once per object. The sets of one object from all the
files are merged in time order, each observation keeping its site. An observation given in two
files (the same site and type, times within the coarser file's time resolution: its format's,
e.g. 0.0864 s for MPC 80-column, or the step its times are rounded to, e.g. a whole second;
positions within :data:`DUPLICATE_ARCSEC`) is used once, from the file of finer
time resolution, and the files' notes say how many copies were dropped; two such observations
whose positions differ more are refused naming both files. Two rows of one site and type at the
same position (:data:`SAME_POSITION_ARCSEC`) with times within :data:`SAME_POSITION_S` are one
measurement given or reduced twice, in one file or two: the later is dropped and the file's note
says how many. Within one file nothing else is a repeat: exposures a fraction of a second apart
(a dense survey, video frames) differ in their angles by the object's motion and their noise.

Times are TU elapsed since a working epoch (:data:`READ_EPOCH`, leap seconds counted): the fit
moves them to its own epoch (:func:`cistrack.fitting.arcs.in_time_base`, bit for bit the clock
arithmetic when no leap second lies between that epoch and an observation) and writes the merged
set into the results directory (:func:`write_merged`).
"""
from __future__ import annotations

import logging
import math
import os
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from cistrack import units
from cistrack.errors import ConfigError, MeasurementError, clipped
from cistrack.fitting.fit_replacing import FIT_RECORD
from cistrack.interfaces.reader import not_a_file
from cistrack.model.measurement import KIND_NAMES, MeasurementSet, kind_of_names
from cistrack.plugin.registry import Registry
from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.output_paths import FIT_STARTED
from cistrack.runs.observation_files import SeveralObjectsError, read_checked, reader_for, write_observations
from cistrack.runs.run_inputs import reading_own_copies, weights_note

__all__ = ["ObjectObservations", "read_object_observations", "merge_sets", "write_merged", "data_kind",
           "READ_EPOCH", "UNNAMED", "DUPLICATE_ARCSEC", "SAME_POSITION_S", "SAME_POSITION_ARCSEC",
           "MAX_FILE_MB", "MAX_FILE_MB_ENV", "max_file_mb", "check_file_sizes", "copies_read_quietly",
           "distinct_names"]

READ_EPOCH = "2000-01-01T00:00:00Z"
"""UTC epoch the files are read against (times TU since it) before the fit's own epoch is known."""

UNNAMED = "object"
"""Designation of observations whose file names no object."""

MAX_FILE_MB = 50.0
"""Default largest observation file read, MB (10^6 bytes): some 300,000 ADES PSV lines."""

MAX_FILE_MB_ENV = "CISTRACK_MAX_FILE_MB"
"""Environment variable that replaces :data:`MAX_FILE_MB` (``cistrack fit --max-file-mb`` sets it)."""

DUPLICATE_ARCSEC = 5.0
"""Largest angle (arcsec) between two observations of one site at (nearly) the same time in two
files for them to be the same observation given twice: well above the 0.015 arcsec rounding of
MPC 80-column angles and the motion of a cislunar object in a rounded time (0.04 s)."""

SAME_POSITION_S = 1.0
"""Largest time apart (s) of two observations of one site and type at the same position (within
:data:`SAME_POSITION_ARCSEC`) for the later to be a repeat of the earlier, in one file or two:
one measurement reduced twice with its time rounded differently (to 1e-5 day, 0.864 s, as MPC
80-column times are, or to a whole second)."""

SAME_POSITION_ARCSEC = 0.001
"""Largest angle (arcsec) between two such observations for them to be at the same position (one
value written twice agrees to 1e-9 arcsec): two exposures' angles carry independent noise of
some 0.1-1 arcsec, so two that agree this closely are one measurement given twice (by chance
once in some 10^6 pairs of a stationary object at 0.5 arcsec noise; a cislunar object moves
0.1-0.5 arcsec in a second besides)."""

_PAD_S = 2e-6
"""Slack (s) on every time comparison: times are TU since :data:`READ_EPOCH`, whose float64
rounding moves a difference of rows 26 years after it by up to some 5e-7 s (rows exactly a
limit apart had been told apart by it)."""


def __getattr__(name: str) -> Any:
    """``REPEAT_S`` (0.25 s) with a DeprecationWarning, until the next release: rows of one file
    that close are repeats only at the same position now (:data:`SAME_POSITION_S`)."""
    if name == "REPEAT_S":
        import warnings

        warnings.warn("cistrack.fitting.observation_input.REPEAT_S no longer sets a rule: rows of one file are "
                      "repeats only at the same position (SAME_POSITION_ARCSEC) within SAME_POSITION_S; the old "
                      "value 0.25 is kept, with this warning, until the next release", DeprecationWarning, stacklevel=2)
        return 0.25
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass
class ObjectObservations:
    """The observations of one object from all the files.

    Attributes
    ----------
    designation : str        the object's designation (:data:`UNNAMED` when no file names it)
    measurements : MeasurementSet  times TU since :data:`READ_EPOCH`, rad, per-row sites
    files : list of str      the files that hold them
    notes : list of str      one line per file on its weights (file's own, or the reader's default)
    """

    designation: str
    measurements: MeasurementSet
    files: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _reader(path: Path, params: dict[str, Any], registry: Registry) -> tuple[Any, list[MeasurementSet] | None]:
    """The reader of ``path`` by suffix, or (no suffix claimed) the first registered reader that
    reads it, with the sets it already read in the latter case."""
    try:
        return reader_for(path, params.get("name"), registry, **_params(params)), None
    except MeasurementError as exc:
        if "no reader recognises" not in str(exc):
            raise
        suffix_error = exc
    tried = []
    for entry in registry.entries("reader"):
        try:
            reader = registry.create("reader", entry.name, **_params(params))
            return reader, [reader.read(path, READ_EPOCH)]
        except SeveralObjectsError:
            return registry.create("reader", entry.name, **_params(params)), None
        except Exception as exc:  # noqa: BLE001 - each format says why it is not this one
            tried.append(f"{entry.name}: {str(exc).splitlines()[0][:160]}")
    raise MeasurementError(f"{suffix_error}; no reader reads its content either ("
                           + "; ".join(tried) + ")") from None


def max_file_mb() -> float:
    """The largest observation file read, MB (10^6 bytes): :data:`MAX_FILE_MB_ENV` when set, else
    :data:`MAX_FILE_MB`. ConfigError naming the variable when it is not a positive number."""
    text = os.environ.get(MAX_FILE_MB_ENV, "").strip()
    if not text:
        return MAX_FILE_MB
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and math.isfinite(value)):
        raise ConfigError(f"environment variable {MAX_FILE_MB_ENV}={text!r}: must be a finite, positive number of MB "
                          f"(default {MAX_FILE_MB:g})")
    return value


def check_file_sizes(paths: list[str | Path]) -> None:
    """Refuse, before reading any, an observation file larger than :func:`max_file_mb` (ConfigError
    naming the file, its size, the limit and how to raise it). Missing files are left to the readers."""
    limit = max_file_mb()
    for p in paths:
        try:
            size = Path(p).stat().st_size if Path(p).is_file() else 0
        except OSError:
            continue
        if size > limit * 1e6:
            raise ConfigError(f"observation file {p}: {size:,} bytes ({size / 1e6:.4g} MB) is larger than the "
                              f"{limit:g} MB limit on "
                              f"an observation file; split it, or raise the limit (cistrack fit --max-file-mb MB, "
                              f"or the environment variable {MAX_FILE_MB_ENV})")


@contextmanager
def copies_read_quietly() -> Iterator[None]:
    """Within it, the readers' warnings (logger ``cistrack.readers``) are dropped: the fit reads
    its own copies of the observations (:func:`write_merged`: ``observations.psv``,
    ``observations-early.psv``) once per attempt, and what a reader has to say of them it said
    of the user's files, by their names, when they were read."""
    logger = logging.getLogger("cistrack.readers")

    def drop(record: logging.LogRecord) -> bool:
        return False
    logger.addFilter(drop)
    try:
        with reading_own_copies():  # nor does the run on them speak of the copies' weights
            yield
    finally:
        logger.removeFilter(drop)


class _SharedParams:
    """Reader parameters given for several files of different formats: each file's reader (by its
    name's suffix) gets those it takes (``check_degrees`` goes to a TDM file's reader only); one
    that no reader of the files takes is refused before any file is read."""

    def __init__(self, params: dict[str, Any], registry: Registry) -> None:
        self.params, self.registry, self.taken = params, registry, set()

    def of(self, path: Path) -> dict[str, Any]:
        from cistrack.interfaces.component import param_specs

        name = str(path).lower()
        claims = [e for e in self.registry.entries("reader")
                  if any(name.endswith(x) for x in getattr(e.factory, "suffixes", ()))]
        if len(claims) != 1 or not isinstance(claims[0].factory, type):
            self.taken.update(self.params)  # no one reader by name: every reader is tried with all of them
            return self.params
        known = param_specs(claims[0].factory)
        mine = {k: v for k, v in self.params.items() if k in known}
        self.taken.update(mine)
        return mine

    def per_file(self, paths: list[str | Path]) -> list[dict[str, Any]]:
        """The parameters of each file's reader; ConfigError for one no reader takes."""
        out = [self.of(Path(p)) for p in paths]
        unused = sorted(set(self.params) - self.taken)
        if unused:
            raise ConfigError(f"reader parameter {unused[0]!r}: no reader of the files given takes it "
                              f"({', '.join(str(p) for p in paths)})")
        return out


def _params(params: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in params.items() if k != "name"}


_TIME_QUANTA_S = (86.4, 8.64, 1.0, 0.864, 0.1, 0.0864, 0.01, 0.001)
"""Time steps a file may round its times to (s), coarsest first: whole seconds and their decimals,
and the decimals of a day (1e-3 to 1e-6 day: MPC 80-column times, written to 5 decimals of a day
by many programs, are 0.864 s apart)."""


def data_time_resolution(ms: MeasurementSet) -> float:
    """The coarsest of :data:`_TIME_QUANTA_S` that every time of ``ms``, counted from its UTC day's
    midnight, is a multiple of (s; 0 when none is: times written to full precision). A file that
    rounds its times to whole seconds, or to 1e-5 day, has that time resolution whatever its format
    allows, and a copy of its observations in another file then differs from them by up to that much."""
    sec = np.asarray(ms.times, dtype=float) * units.TU_S
    if sec.size < 2:
        return 0.0
    first = units.tu_to_utc(units.parse_utc(READ_EPOCH), float(ms.times[0]))
    midnight = first.replace(hour=0, minute=0, second=0, microsecond=0)
    of_day = (first - midnight).total_seconds() + (sec - sec[0])  # no leap second within a file assumed
    for q in _TIME_QUANTA_S:
        if np.all(np.abs(of_day - np.round(of_day / q) * q) < 2e-6):
            return q
    return 0.0


def _read_file(path: Path, params: dict[str, Any], registry: Registry) -> tuple[list[MeasurementSet], float]:
    """The sets of one file, one per object named in it, and the time resolution (s) of its format."""
    why = not_a_file(path)
    if why is not None:
        raise ConfigError(f"observation file {path}: {why}")
    reader, done = _reader(path, params, registry)
    resolution = float(getattr(reader, "time_resolution_s", 0.0))
    if done is not None:
        return done, resolution
    try:
        return [read_checked(reader, path, READ_EPOCH, registry)], resolution
    except SeveralObjectsError as exc:
        name = params.get("name") or type(reader).__name__
        out = []
        for obj in exc.objects:
            one = registry.create("reader", _registered_name(reader, registry, name), **{**_params(params),
                                                                                         "designation": obj})
            out.append(read_checked(one, path, READ_EPOCH, registry))
        return out, resolution


def _require_sites(path: Path, sets: list[MeasurementSet]) -> None:
    """Refuse observations that name no observing site (a CSV without a ``site`` column): a fit
    places every observation at its site."""
    if any(ms.sites is None for ms in sets):
        raise MeasurementError(
            f"observation file {path}: no column 'site', so its observations name no observing site; cistrack fit "
            "needs the site of every observation: add a column 'site' holding, per row, an MPC observatory code "
            "(e.g. 809) or a key declared in the reader's sites parameter (--set 'measurements.reader.sites="
            "{KEY = {latitude_deg = .., longitude_deg = .., height_m = ..}}')")


def _registered_name(reader: Any, registry: Registry, fallback: str) -> str:
    for entry in registry.entries("reader"):
        if entry.factory is type(reader):
            return entry.name
    return fallback


def _site_table(sets: list[MeasurementSet], files: list[str]) -> dict[str, Any]:
    """The sites of all ``sets`` by key; refuses a key given two positions (naming the file)."""
    table: dict[str, Any] = {}
    for ms, f in zip(sets, files):
        for key, site in ms.site_table.items():
            if key in table and table[key] != site:
                raise MeasurementError(f"{f}: site {key!r} has another position than in an earlier file; "
                                       "give each observatory one position")
            table[key] = site
    return table


@dataclass
class _Rows:
    """The observations of several sets side by side: times (TU), angles (n, 2) rad, sigmas (n, 2)
    rad, kinds, sites, and per row the index of its set."""

    times: np.ndarray
    values: np.ndarray
    sigmas: np.ndarray
    kinds: np.ndarray
    sites: np.ndarray
    source: np.ndarray

    @classmethod
    def of(cls, sets: list[MeasurementSet]) -> "_Rows":
        return cls(np.concatenate([ms.times for ms in sets]),
                   np.concatenate([ms.values[:, :2] for ms in sets]),
                   np.concatenate([ms.sigmas[:, :2] for ms in sets]),
                   np.concatenate([[ms.kind_at(i) for i in range(len(ms))] for ms in sets]).astype(str),
                   np.concatenate([[ms.site_at(i) for i in range(len(ms))] for ms in sets]).astype(str),
                   np.concatenate([[k] * len(ms) for k, ms in enumerate(sets)]).astype(int))

    def take(self, index: np.ndarray) -> "_Rows":
        return _Rows(*(a[index] for a in (self.times, self.values, self.sigmas, self.kinds, self.sites, self.source)))


def _close_pairs(rows: _Rows, tol_s: np.ndarray) -> list[tuple[int, int]]:
    """Pairs (i, j) of rows with the same site and type, j the later, that may be one observation:
    their times differ by at most the coarser of their sets' time resolutions ``tol_s`` (s, per
    set), two sets' rows only (one set's distinct times are distinct whatever they are rounded
    to); or by at most :data:`SAME_POSITION_S` at the same position (:data:`SAME_POSITION_ARCSEC`)."""
    secs = units.tu_to_seconds(rows.times)
    order = np.lexsort((secs, rows.sites))
    widest = max(float(tol_s.max()), SAME_POSITION_S) + _PAD_S
    pairs: list[tuple[int, int]] = []
    for shift in range(1, len(order)):
        a, b = order[:-shift], order[shift:]
        dt = secs[b] - secs[a]
        near = (rows.sites[a] == rows.sites[b]) & (dt <= widest)
        if not near.any():
            break
        tol = np.maximum(tol_s[rows.source[a]], tol_s[rows.source[b]])
        timely = (rows.source[a] != rows.source[b]) & (dt <= tol + _PAD_S)
        same_place = _separations_arcsec(rows, a, b) <= SAME_POSITION_ARCSEC
        hit = near & (rows.kinds[a] == rows.kinds[b]) & (timely | same_place)
        pairs += [(int(i), int(j)) for i, j in zip(a[hit], b[hit])]
    return pairs


def _separations_arcsec(rows: _Rows, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Angles between rows ``i`` and ``j`` (index arrays) on the sky (or the az/el sphere), arcsec."""
    (a1, b1), (a2, b2) = rows.values[i].T, rows.values[j].T
    d1 = (a1 - a2 + np.pi) % (2 * np.pi) - np.pi
    return np.hypot(d1 * np.cos(0.5 * (b1 + b2)), b1 - b2) / units.ARCSEC_RAD


def _duplicates(rows: _Rows, files: list[str], tol_s: np.ndarray) -> np.ndarray:
    """Per row, the set index of the copy kept in its place, -1 for a row kept: of each observation
    given in two files (:func:`_close_pairs`, positions within :data:`DUPLICATE_ARCSEC`) the copy
    from the file of coarser time resolution (the later file when equal) is dropped; of a repeat
    within one file the later row (its own set index). MeasurementError naming both files when the
    positions of two files' copies differ more (two rows of one file that do are both kept)."""
    drop = np.full(len(rows.times), -1, dtype=int)
    for i, j in _close_pairs(rows, tol_s):
        sep = float(_separations_arcsec(rows, np.array([i]), np.array([j]))[0])
        if rows.source[i] == rows.source[j]:
            if sep <= DUPLICATE_ARCSEC and drop[i] < 0:
                drop[j] = rows.source[j]
            continue
        fi, fj = files[rows.source[i]], files[rows.source[j]]
        if sep > DUPLICATE_ARCSEC:
            when = units.format_utc(units.tu_to_utc(units.parse_utc(READ_EPOCH), float(rows.times[i])))[:23]
            raise MeasurementError(
                f"site {str(rows.sites[i])!r} observed at {when}Z in {fi} and {fj} (times within "
                f"{max(tol_s[rows.source[i]], tol_s[rows.source[j]]):g} s, the coarser file's time resolution) at "
                f"positions {sep:.3g} arcsec apart (the same observation given twice with different values?); "
                "give each observation once")
        worse, better = sorted((i, j), key=lambda k: (tol_s[rows.source[k]], rows.source[k]), reverse=True)
        drop[worse] = rows.source[better]
    return drop


def _refuse_same_file_twice(paths: list[str | Path]) -> None:
    """ConfigError naming two of ``paths`` that are one file (the same path, or two spellings or a
    link of it): every observation in it would be read twice and the copy dropped as a duplicate."""
    seen: list[tuple[str | Path, tuple[int, int]]] = []
    for p in paths:
        try:
            st = os.stat(p)
        except OSError:
            continue  # a missing file is the reader's to name
        key = (st.st_dev, st.st_ino)
        first = next((q for q, k in seen if k == key), None)
        if first is not None:
            raise ConfigError(f"{p}: the same file as {first}, given before it; give each file once")
        seen.append((p, key))


def distinct_names(paths: list[str | Path]) -> list[str]:
    """Each path as its last parts, as few as tell it from the other paths (``a/obs.psv`` and
    ``b/obs.psv``, not ``obs.psv`` twice); the same path given twice is named alike."""
    parts = [Path(p).parts or (str(p),) for p in paths]
    names = []
    for k, mine in enumerate(parts):
        others = [o for j, o in enumerate(parts) if j != k and o != mine]
        n = 1
        while n < len(mine) and any(o[-n:] == mine[-n:] for o in others):
            n += 1
        names.append(str(Path(*mine[-n:])))
    return names


_SAME_WORDS = f"times within {SAME_POSITION_S:g} s at the same position to {SAME_POSITION_ARCSEC:g} arcsec"
"""The rule for a repeat within one file, as a note states it."""


def _duplicate_notes(rows: _Rows, drop: np.ndarray, files: list[str], tol_s: np.ndarray) -> list[str]:
    """One line per file that lost observations as duplicates (``drop`` from :func:`_duplicates`):
    first its repeats within itself, then its copies of other files' observations."""
    notes, shown = [], distinct_names(files)
    for k in sorted(set(rows.source[drop >= 0].tolist())):
        again = (drop == k) & (rows.source == k)
        if again.any():
            notes.append(f"{shown[k]}: {int(np.count_nonzero(again))} observations dropped as repeats within the "
                         f"file (the same site and type as an earlier row, {_SAME_WORDS}: one observation given "
                         "twice, or reduced twice?); the later row of each such pair is not used")
        mine = (drop >= 0) & (drop != k) & (rows.source == k)
        if not mine.any():
            continue
        kept = ", ".join(shown[m] for m in sorted(set(drop[mine].tolist())))
        notes.append(f"{shown[k]}: {int(np.count_nonzero(mine))} observations dropped as duplicates of "
                     f"those in {kept} (same site and type, times within {tol_s[k]:g} s and positions within "
                     f"{DUPLICATE_ARCSEC:g} arcsec, or within {SAME_POSITION_S:g} s at the same position); the copy "
                     "with the finer times is used")
    return notes


def _merge(sets: list[MeasurementSet], files: list[str],
           time_resolutions: list[float] | None = None) -> tuple[MeasurementSet, list[str]]:
    """:func:`merge_sets` and one note per file whose duplicates were dropped."""
    tol_s = np.asarray(time_resolutions if time_resolutions is not None else [0.0] * len(sets), dtype=float)
    rows = _Rows.of(sets)
    drop = _duplicates(rows, files, tol_s)
    if len(sets) == 1 and not (drop >= 0).any():
        return sets[0], []
    table = _site_table(sets, files)
    notes = _duplicate_notes(rows, drop, files, tol_s)
    kept = rows.take(np.nonzero(drop < 0)[0])
    r = kept.take(np.lexsort((kept.sites, kept.times)))
    names = KIND_NAMES[r.kinds[0]] if len(set(r.kinds.tolist())) == 1 and r.kinds[0] in KIND_NAMES \
        else ("angle_1", "angle_2")
    meta = dict(sets[0].meta)
    meta["source"] = ", ".join(files)
    for key in ("default_sigma_count", "default_sigma_partial"):
        meta[key] = int(sum(min(ms.meta.get(key, 0), int(np.count_nonzero(r.source == k)))
                            for k, ms in enumerate(sets)))
    if (drop >= 0).any():
        meta["duplicates_dropped"] = int(np.count_nonzero(drop >= 0))
    ms = MeasurementSet(r.times, r.values, r.sigmas, names, meta, sites=r.sites, kinds=r.kinds, site_table=table)
    return ms, notes


def merge_sets(sets: list[MeasurementSet], files: list[str],
               time_resolutions: list[float] | None = None) -> MeasurementSet:
    """One set of the observations of ``sets`` (same epoch), in time order.

    An observation given in two files (same site and type, times within the coarser file's
    ``time_resolutions`` entry, s per set; 0 s when absent; positions within
    :data:`DUPLICATE_ARCSEC`) is used once, from the file of finer time resolution, and so is one
    given twice at the same position (:data:`SAME_POSITION_ARCSEC`) within :data:`SAME_POSITION_S`,
    in one set or two (the later row is dropped); meta
    ``duplicates_dropped`` counts the copies dropped. Refuses such a pair whose positions differ
    more, and a site key given two positions (MeasurementError naming the files)."""
    return _merge(sets, files, time_resolutions)[0]


def read_object_observations(paths: list[str | Path], registry: Registry,
                             reader_params: dict[str, Any] | None = None,
                             log: Callable[[str], None] | None = None) -> list[ObjectObservations]:
    """The observations in ``paths``, one :class:`ObjectObservations` per object (in order of first
    appearance). ``reader_params``: parameters for every reader (``sigma_arcsec``, ``sites``;
    ``name`` forces one format). Raises MeasurementError / ConfigError naming the file."""
    say = log or (lambda m: None)
    if not paths:
        raise ConfigError("no observation files given; give one or more files (ADES .psv/.xml, MPC 80-column, "
                          "CCSDS .tdm, cistrack .csv)")
    check_file_sizes(paths)
    _refuse_same_file_twice(paths)
    params = dict(reader_params or {})
    by_object: dict[str, tuple[list[MeasurementSet], list[str], list[float]]] = {}
    notes: dict[str, list[str]] = {}
    per_file = _SharedParams(params, registry).per_file(paths) if len(paths) > 1 and not params.get("name") \
        else [params] * len(paths)
    for p, file_params, shown in zip(paths, per_file, distinct_names(paths)):
        path = Path(p)
        found, resolution = _read_file(path, file_params, registry)
        _require_sites(path, found)
        for ms in found:
            obj = str(ms.meta.get("object") or UNNAMED)
            sets, files, resolutions = by_object.setdefault(obj, ([], [], []))
            sets.append(ms)
            files.append(str(path))
            resolutions.append(max(resolution, data_time_resolution(ms)))
            note = weights_note(ms)
            notes.setdefault(obj, []).append(f"{shown}: {len(ms)} observations of {clipped(obj)}"
                                             + (f"; {note}" if note else ""))
            say(notes[obj][-1])
    unused = _unused_sigma(params, [ms for sets, _, _ in by_object.values() for ms in sets])
    if unused:
        say(f"warning: {unused}")
    twins = _case_twins(list(by_object))
    for line in twins.values():
        say(f"warning: {line}")
    out = []
    for obj, (sets, files, resolutions) in by_object.items():
        merged, dropped = _merge(sets, files, resolutions)
        for line in dropped:
            say(line)
        told = [unused] * bool(unused) + ([twins[obj]] if obj in twins else [])
        out.append(ObjectObservations(obj, merged, files, notes[obj] + dropped + told))
    return out


def _case_twins(names: list[str]) -> dict[str, str]:
    """For each designation that another one equals but for letter case or surrounding blanks
    ('dro' and 'DRO'), the words saying they are fitted as separate objects ({} when none)."""
    groups: dict[str, list[str]] = {}
    for name in names:
        groups.setdefault(name.strip().casefold(), []).append(name)
    out = {}
    for same in (g for g in groups.values() if len(g) > 1):
        shown = " and ".join(repr(clipped(n)) for n in same)
        words = (f"the designations {shown} differ only in letter case or blanks: they are fitted as "
                 f"{len(same)} separate objects; write them alike in the files if they are one")
        out.update({n: words for n in same})
    return out


def _unused_sigma(params: dict[str, Any], sets: list[MeasurementSet]) -> str:
    """A warning when the reader parameter ``sigma_arcsec`` was given but no observation took it
    (every row of every file states its own uncertainties; probe N1: it was accepted and changed
    nothing), naming the way to replace the files' own; "" otherwise."""
    counts = [ms.meta.get("default_sigma_count") for ms in sets]
    if "sigma_arcsec" not in params or not counts or any(n is None or n > 0 for n in counts):
        return ""
    return (f"measurements.reader.sigma_arcsec={params['sigma_arcsec']!r} applies to no observation: every "
            "row states its own uncertainties (rmsRA/rmsDec), which are used; to replace them, add --set "
            "measurements.reader.sigma_from_file=false (docs/observation-formats.md, 'Weights')")


def write_merged(path: Path, measurements: MeasurementSet, designation: str, registry: Registry) -> str:
    """Write ``measurements`` (TU since :data:`READ_EPOCH`) to ``path`` as ADES PSV (RA/Dec) or
    CCSDS TDM (other angle types), with the designation; returns the suffix used (".psv"/".tdm")."""
    marker = path.parent / FIT_STARTED  # first: a fit stopped before its records may be retried here
    if not marker.is_file():
        write_text_atomic(marker, f"cistrack fit of {designation}\n")
    # then the record of an earlier fit here goes: stopped after these observations replaced its own,
    # a redo had left it beside them, and export and predict used its orbit (probe I2)
    (path.parent / FIT_RECORD).unlink(missing_ok=True)
    ms = measurements.subset(np.ones(len(measurements), dtype=bool))
    ms.meta["object"] = designation
    kinds = {ms.kind_at(i) for i in range(len(ms))}
    fmt, suffix = ("ades-psv", ".psv") if kinds == {"radec"} else ("tdm", ".tdm")
    write_observations(path.with_suffix(suffix), ms, READ_EPOCH, format=fmt, registry=registry)
    return suffix


def data_kind(measurements: MeasurementSet) -> str:
    """The measurement type of the set ("radec" or "azel"); MeasurementError for a mixed set."""
    kinds = {measurements.kind_at(i) for i in range(len(measurements))} - {""}
    if not kinds:
        kinds = {kind_of_names(measurements.names)}
    if len(kinds) != 1:
        raise MeasurementError(f"the observations mix measurement types {sorted(kinds)}; fit one type at a time")
    return kinds.pop()
