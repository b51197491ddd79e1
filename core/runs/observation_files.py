"""Observation files: reading and writing through the registered readers, and the shared
line-and-field error of every format.

    mset = read_observations("obs.psv", epoch="2026-01-01T00:00:00Z")        # format from the suffix
    mset = read_observations("obs.txt", epoch=..., format="mpc80")            # or named
    write_observations("obs.tdm", mset, epoch=..., format="tdm")
"""
from __future__ import annotations

from datetime import datetime
from os import PathLike
from pathlib import Path
from typing import Any

from cistrack.errors import MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry, default_registry

__all__ = ["read_observations", "write_observations", "reader_for", "FieldError", "SeveralObjectsError", "field_error",
           "show_field", "read_text_lines"]

_SHOWN = 40


class FieldError(MeasurementError):
    """A malformed field of an observation file: names the file, the line (from 1) and the field."""

    def __init__(self, path: str | PathLike, line: int, fieldname: str, reason: str):
        self.path, self.line, self.field, self.reason = str(path), int(line), fieldname, reason
        super().__init__(f"{path}, line {line}, field {fieldname}: {reason}")


class SeveralObjectsError(MeasurementError):
    """An observation file names several objects (designations ``objects``, in file order) and
    the reader was not told which one to read (reader parameter ``designation``)."""

    def __init__(self, path: str | PathLike, objects: list[str]):
        self.path, self.objects = str(path), list(objects)
        shown = ", ".join(repr(o) for o in self.objects[:10]) + (", ..." if len(self.objects) > 10 else "")
        super().__init__(f"{path}: holds observations of {len(self.objects)} objects ({shown}); read one at a "
                         f"time with the reader parameter designation (e.g. [measurements] reader = {{ name = "
                         f"..., designation = {self.objects[0]!r} }}), or give the file to 'cistrack fit', "
                         f"which fits each object")


def show_field(text: str) -> str:
    """The offending field's text for a message, quoted and cut to 40 characters (never more
    of the file than the field itself)."""
    t = str(text)
    return repr(t if len(t) <= _SHOWN else t[:_SHOWN] + "...")


def field_error(path, line: int, fieldname: str, reason: str) -> FieldError:
    return FieldError(path, line, fieldname, reason)


def read_text_lines(path: str | PathLike) -> list[str]:
    """The lines of a UTF-8 text file (a leading byte-order mark is dropped), with a
    MeasurementError naming the file if unreadable."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise MeasurementError(f"cannot read observation file {p}: {exc.strerror or exc}") from exc
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise FieldError(p, line, "(encoding)", f"not UTF-8 text ({exc.reason})") from None
    if "\x00" in text:
        line = text[:text.index("\x00")].count("\n") + 1
        raise FieldError(p, line, "(encoding)", "contains a NUL byte: not a text file")
    return text.splitlines()


def reader_for(path: str | PathLike, format: str | None = None, registry: Registry | None = None,
               **params: Any):
    """The reader component for ``format`` (a registered reader name), or the one whose
    suffixes match ``path`` when ``format`` is None."""
    reg = registry or default_registry()
    if Path(path).is_dir():
        raise MeasurementError(f"{path}: is a directory, not an observation file; give the path of a file "
                               "(e.g. [measurements] file = \"obs.psv\")")
    if format is not None:
        return reg.create("reader", format, **params)
    name = str(path).lower()
    matches = [e.name for e in reg.entries("reader")
               if any(name.endswith(s) for s in getattr(e.factory, "suffixes", ()))]
    if len(matches) != 1:
        known = {e.name: list(getattr(e.factory, "suffixes", ())) for e in reg.entries("reader")}
        why = ("not an observation file of any known format: no reader recognises" if not matches
               else f"several readers ({', '.join(matches)}) recognise")
        raise MeasurementError(f"{path}: {why} this file name; give a file whose name ends in a known "
                               f"suffix, or name the format (one of {', '.join(f'{k} {v}' for k, v in known.items())})")
    return reg.create("reader", matches[0], **params)


def read_observations(path: str | PathLike, epoch: str | datetime, format: str | None = None,
                      registry: Registry | None = None, **params: Any) -> MeasurementSet:
    """Read an observation file with the reader ``format`` (or the one matching its suffix);
    ``params`` are the reader's parameters (default sigmas, explicit sites, ...)."""
    return reader_for(path, format, registry, **params).read(path, epoch)


def write_observations(path: str | PathLike, measurements: MeasurementSet, epoch: str | datetime,
                       format: str | None = None, registry: Registry | None = None, **params: Any) -> None:
    """Write ``measurements`` with the reader ``format`` (or the one matching the suffix)."""
    reader_for(path, format, registry, **params).write(path, measurements, epoch)
