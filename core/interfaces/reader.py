"""Reader: an observation file format, read into a MeasurementSet and written back out; and what
every format shares: the line-and-field error of a malformed file (:class:`FieldError`), the
error of a file holding several objects (:class:`SeveralObjectsError`), reading a file's text
lines (:func:`read_text_lines`) and quoting an offending field (:func:`show_field`)."""
from __future__ import annotations

import errno
import os
import re
import stat
from abc import abstractmethod
from datetime import datetime
from os import PathLike
from pathlib import Path
from typing import ClassVar

from cistrack.errors import MeasurementError
from cistrack.interfaces.component import Component
from cistrack.model.measurement import MeasurementSet

__all__ = ["Reader", "FieldError", "SeveralObjectsError", "show_field", "field_error", "read_text_lines",
           "split_lines", "not_a_file"]

_SHOWN = 40


class Reader(Component):
    """An observation file format (registry kind ``"reader"``).

    ``read`` turns a file into a :class:`~cistrack.model.measurement.MeasurementSet` with times in TU
    elapsed since ``epoch`` (the scenario's UTC epoch; leap seconds between count, see
    :func:`cistrack.units.utc_to_tu`), angles in rad, ranges in LU, and per-measurement
    site keys and types where the format has them; ``write`` writes a set so that ``read`` gives
    it back (to the format's stated resolution). A malformed file raises
    :class:`~cistrack.errors.MeasurementError` naming the file, the line and the field, and never
    quotes more of the file than the offending field.
    """

    kind = "reader"
    suffixes: ClassVar[tuple[str, ...]] = ()
    """File-name endings this format is recognised by (lower case, e.g. (".psv",))."""
    measurement_kinds: ClassVar[tuple[str, ...]] = ("azel",)
    """Measurement types the format carries ("azel", "radec")."""
    time_resolution_s: ClassVar[float] = 1e-6
    """Resolution of the times the writer writes, seconds (a round trip is exact to it)."""
    angle_resolution_rad: ClassVar[float] = 0.0
    """Resolution of the angles written, rad; 0: angles and sigmas round-trip bit for bit."""
    carries_sigmas: ClassVar[bool] = True
    """Whether per-measurement sigmas are written (otherwise the reader's defaults come back)."""

    @abstractmethod
    def read(self, path: str | PathLike, epoch: str | datetime) -> MeasurementSet:
        """Measurements of the file at ``path``; t = 0 at ``epoch`` (UTC)."""

    @abstractmethod
    def write(self, path: str | PathLike, measurements: MeasurementSet, epoch: str | datetime) -> None:
        """Write ``measurements`` (times TU since ``epoch``) to ``path``."""


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


_NOT_REGULAR = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                (stat.S_ISFIFO, "a named pipe (fifo)"), (stat.S_ISSOCK, "a socket"))


def not_a_file(path: str | PathLike) -> str | None:
    """Why ``path`` cannot be read as an observation file, for a message after its name ("no such
    file", "is a directory, not a file", "is not a regular file: a character device", "is a loop
    of symbolic links", ...), or None when it is a regular file (or a link to one). Nothing is
    opened: a pipe or a device is never read."""
    if str(path) == "-" and not os.path.lexists(path):
        return "standard input is not read: give the name of an observation file"
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a loop of symbolic links"
        if exc.errno == errno.ENOENT and os.path.islink(path):
            return f"is a symbolic link to a missing file ({os.readlink(os.fspath(path))})"
        return "no such file" if exc.errno in (errno.ENOENT, errno.ENOTDIR) else f"cannot be examined: {exc.strerror}"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "is a directory, not a file"
    kind = next((what for test, what in _NOT_REGULAR if test(mode)), "not a file of data")
    return f"is not a regular file: {kind}"


_LINE_BREAK = re.compile(r"\r\n|\r|\n")


def split_lines(text: str) -> list[str]:
    """The lines of ``text``, split at line breaks only: LF, CR LF and CR (str.splitlines also
    splits at form feeds, U+2028, U+0085, ..., which a comment may hold). A break at the end of
    the text ends the last line (as splitlines: no empty line after it)."""
    lines = _LINE_BREAK.split(text)
    if lines[-1] == "":
        lines.pop()
    return lines


def _line_of(text: str) -> int:
    """The line (from 1) on which the end of ``text`` lies."""
    return len(_LINE_BREAK.findall(text)) + 1


_XML_ENCODING = re.compile(rb"""\A(?:\xef\xbb\xbf)?\s*<\?xml[^>]*?\bencoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def _declared_encoding(data: bytes) -> str:
    """For a file that is not UTF-8: what its XML declaration says of that ("" for none, or one
    declaring UTF-8). An ADES XML file declaring ISO-8859-1 (valid XML) had been told only "not
    UTF-8 text (invalid start byte)"."""
    found = _XML_ENCODING.match(data[:1024])
    name = found[1].decode("ascii") if found else ""
    if not name or name.lower().replace("_", "-") in ("utf-8", "utf8"):
        return ""
    return (f": the file declares encoding=\"{name}\", and cistrack reads XML observation files (ADES XML) in "
            f"UTF-8 only; convert it, e.g. iconv -f {name} -t UTF-8, and declare encoding=\"UTF-8\"")


def read_text_lines(path: str | PathLike) -> list[str]:
    """The lines of a UTF-8 text file (a leading byte-order mark is dropped; lines end at LF, CR LF
    or CR: :func:`split_lines`), with a MeasurementError naming the file if it is not a regular
    file (:func:`not_a_file`) or unreadable."""
    p = Path(path)
    why = not_a_file(p)
    if why is not None:
        raise MeasurementError(f"observation file {p}: {why}")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise MeasurementError(f"cannot read observation file {p}: {exc.strerror or exc}") from exc
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = _line_of(data[:exc.start].decode("utf-8-sig", errors="replace"))
        raise FieldError(p, line, "(encoding)", f"not UTF-8 text ({exc.reason}){_declared_encoding(data)}") from None
    if "\x00" in text:
        raise FieldError(p, _line_of(text[:text.index("\x00")]), "(encoding)", "contains a NUL byte: not a text file")
    return split_lines(text)
