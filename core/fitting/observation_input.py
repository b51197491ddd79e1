"""Observation files in, one measurement set per object out: what ``cistrack fit`` reads.

Each file is read by the registered reader its name's suffix names (``.psv``, ``.xml``, ``.tdm``,
...); a file whose suffix no reader claims is offered to every registered reader in turn and taken by the
first that reads it. A file naming several objects (ADES permID / provID / trkSub, the MPC 80-column
designation, TDM ``PARTICIPANT_2``) is read once per object. The sets of one object from all the
files are merged in time order, each observation keeping its site; an observation given twice
(the same site and time in two files) is refused naming both files.

Times are TU since a working epoch (:data:`READ_EPOCH`): the fit moves them to its own epoch by
writing the merged set into the results directory (:func:`write_merged`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from cistrack.errors import ConfigError, MeasurementError
from cistrack.model.measurement import KIND_NAMES, MeasurementSet, kind_of_names
from cistrack.plugin.registry import Registry
from cistrack.runs.observation_files import SeveralObjectsError, reader_for, write_observations
from cistrack.runs.run_inputs import weights_note

__all__ = ["ObjectObservations", "read_object_observations", "merge_sets", "write_merged", "data_kind",
           "READ_EPOCH", "UNNAMED"]

READ_EPOCH = "2000-01-01T00:00:00Z"
"""UTC epoch the files are read against (times TU since it) before the fit's own epoch is known."""

UNNAMED = "object"
"""Designation of observations whose file names no object."""


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


def _params(params: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in params.items() if k != "name"}


def _read_file(path: Path, params: dict[str, Any], registry: Registry) -> list[MeasurementSet]:
    """The sets of one file, one per object named in it."""
    if not path.is_file():
        raise ConfigError(f"observation file {path}: " + ("is a directory, not a file" if path.is_dir()
                                                           else "no such file"))
    reader, done = _reader(path, params, registry)
    if done is not None:
        return done
    try:
        return [reader.read(path, READ_EPOCH)]
    except SeveralObjectsError as exc:
        name = params.get("name") or type(reader).__name__
        out = []
        for obj in exc.objects:
            one = registry.create("reader", _registered_name(reader, registry, name), **{**_params(params),
                                                                                         "designation": obj})
            out.append(one.read(path, READ_EPOCH))
        return out


def _registered_name(reader: Any, registry: Registry, fallback: str) -> str:
    for entry in registry.entries("reader"):
        if entry.factory is type(reader):
            return entry.name
    return fallback


def merge_sets(sets: list[MeasurementSet], files: list[str]) -> MeasurementSet:
    """One set of the observations of ``sets`` (same epoch), in time order; refuses a site and
    time given twice (naming the two files) and a site key given two positions."""
    if len(sets) == 1:
        return sets[0]
    table: dict[str, Any] = {}
    for ms, f in zip(sets, files):
        for key, site in ms.site_table.items():
            if key in table and table[key] != site:
                raise MeasurementError(f"{f}: site {key!r} has another position than in an earlier file; "
                                       "give each observatory one position")
            table[key] = site
    times = np.concatenate([ms.times for ms in sets])
    values = np.concatenate([ms.values[:, :2] for ms in sets])
    sigmas = np.concatenate([ms.sigmas[:, :2] for ms in sets])
    kinds = np.concatenate([[ms.kind_at(i) for i in range(len(ms))] for ms in sets]).astype(str)
    sites = np.concatenate([[ms.site_at(i) for i in range(len(ms))] for ms in sets]).astype(str)
    origin = np.concatenate([[f] * len(ms) for ms, f in zip(sets, files)])
    order = np.lexsort((sites, times))
    times, values, sigmas, kinds, sites, origin = (a[order] for a in (times, values, sigmas, kinds, sites, origin))
    same = np.nonzero((np.diff(times) == 0) & (sites[1:] == sites[:-1]))[0]
    if same.size:
        i = int(same[0])
        raise MeasurementError(f"site {str(sites[i])!r} observed at the same time in {origin[i]} and {origin[i + 1]} "
                               "(the same observation given twice?); give each observation once")
    one_kind = set(kinds.tolist())
    names = KIND_NAMES[kinds[0]] if len(one_kind) == 1 and kinds[0] in KIND_NAMES else ("angle_1", "angle_2")
    meta = dict(sets[0].meta)
    meta["source"] = ", ".join(files)
    meta["default_sigma_count"] = int(sum(ms.meta.get("default_sigma_count", 0) for ms in sets))
    return MeasurementSet(times, values, sigmas, names, meta, sites=sites, kinds=kinds, site_table=table)


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
    params = dict(reader_params or {})
    by_object: dict[str, tuple[list[MeasurementSet], list[str]]] = {}
    notes: dict[str, list[str]] = {}
    for p in paths:
        path = Path(p)
        for ms in _read_file(path, params, registry):
            obj = str(ms.meta.get("object") or UNNAMED)
            sets, files = by_object.setdefault(obj, ([], []))
            sets.append(ms)
            files.append(str(path))
            note = weights_note(ms)
            notes.setdefault(obj, []).append(f"{path.name}: {len(ms)} observations of {obj}"
                                             + (f"; {note}" if note else ""))
            say(notes[obj][-1])
    out = []
    for obj, (sets, files) in by_object.items():
        out.append(ObjectObservations(obj, merge_sets(sets, files), files, notes[obj]))
    return out


def write_merged(path: Path, measurements: MeasurementSet, designation: str, registry: Registry) -> str:
    """Write ``measurements`` (TU since :data:`READ_EPOCH`) to ``path`` as ADES PSV (RA/Dec) or
    CCSDS TDM (other angle types), with the designation; returns the suffix used (".psv"/".tdm")."""
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
