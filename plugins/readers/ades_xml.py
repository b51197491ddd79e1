"""IAU ADES observations in XML: reader ``"ades-xml"`` (suffix .xml).

``<ades version="2022"><obsBlock><obsData><optical> ... </optical></obsData></obsBlock></ades>``;
each ``<optical>`` element is one observation whose child elements are the ADES fields (see
:mod:`cistrack.plugins.readers.ades_records`). Parsed with expat (no DTDs, no external
entities are fetched) keeping the line of every element, so errors name the line and field.
"""
from __future__ import annotations

from pathlib import Path
from xml.parsers import expat

from cistrack.api import hookimpl
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.reader import FieldError, read_text_lines, show_field

from .ades_records import (POS_FIELDS, WRITE_FIELDS, AdesReader, is_radar, record_to_row, rows_for_writing, say_skipped,
                           say_tiny_sigmas)
from .ades_psv import ADES_VERSIONS
from .obs_rows import build_set, parse_epoch

__all__ = ["AdesXmlReader"]


def _escape(text: str) -> str:
    """``&``, ``<`` and ``>`` as XML entities (what xml.sax.saxutils.escape does; that module
    imports urllib.request, ~12 ms of every start-up that lists the readers)."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


class _OpticalCollector:
    """expat handlers that collect every <optical> element as (line, {field: (text, line)})."""

    def __init__(self, path, parser) -> None:
        self.path, self.parser = path, parser
        self.out: list[tuple[int, dict]] = []
        self.root: str | None = None
        self.rec: dict | None = None  # the <optical> being read
        self.line = 0  # its line
        self.field: str | None = None  # the field element being read, its text pieces and line
        self.buf: list[str] = []
        self.fline = 0
        self.skipped: dict[str, int] = {}  # other ADES observation elements (<radar>, ...) by name
        self.stack: list[str] = []  # the open elements

    def start(self, name, attrs) -> None:
        line = self.parser.CurrentLineNumber
        if self.root is None:
            self._root(name, attrs, line)
        parent = self.stack[-1] if self.stack else None
        self.stack.append(name)
        if name in _PARENT and parent != _PARENT[name]:
            raise FieldError(self.path, line, f"<{name}>", f"inside <{(parent or '(none)')[:40]}>; an ADES <{name}> "
                                                           f"belongs in <{_PARENT[name]}>")
        if name == "optical":
            if self.rec is not None:
                raise FieldError(self.path, line, "<optical>", "an <optical> element inside another")
            self.rec, self.line = {}, line
        elif name in OTHER_OBSERVATIONS and self.rec is None:
            self.skipped[name] = self.skipped.get(name, 0) + 1
        elif self.rec is not None:
            if self.field is not None:
                raise FieldError(self.path, line, self.field, f"contains an element <{name[:40]}>; ADES fields are text")
            if attrs:  # <ra unit="rad"> would be read as degrees
                raise FieldError(self.path, line, name, f"has attributes ({', '.join(a[:40] for a in attrs)}); ADES fields "
                                                        "take none: their units are fixed (degrees, arcsec, ...)")
            self.field, self.buf, self.fline = name, [], line

    def _root(self, name: str, attrs: dict, line: int) -> None:
        self.root = name
        if name != "ades":
            raise FieldError(self.path, line, "<ades>", f"the root element is <{name[:40]}>, not <ades>")
        if attrs.get("xmlns"):  # ADES elements have no namespace: another vocabulary's <ades>
            raise FieldError(self.path, line, "<ades>", f"in the namespace {attrs['xmlns'][:80]!r}; ADES elements "
                                                         "have none")
        version = attrs.get("version")
        if version is not None and version.strip() not in ADES_VERSIONS:
            raise FieldError(self.path, line, "version", f"{show_field(version)}: ADES versions "
                                                         f"{' and '.join(ADES_VERSIONS)} are read")

    def end(self, name) -> None:
        self.stack.pop()
        if name == "optical":
            self.out.append((self.line, self.rec))
            self.rec = None
        elif self.rec is not None and self.field == name:
            if name in self.rec:
                raise FieldError(self.path, self.fline, name, "field given twice in one observation")
            self.rec[name] = ("".join(self.buf), self.fline)
            self.field = None

    def chars(self, data) -> None:
        if self.field is not None:
            self.buf.append(data)

    def no_entities(self, *_args) -> None:
        raise FieldError(self.path, self.parser.CurrentLineNumber, "(DOCTYPE)",
                         "DTDs and entity declarations are not allowed")


_PARENT = {"obsBlock": "ades", "obsData": "obsBlock", "optical": "obsData"}
"""Where each structural ADES element belongs."""
OTHER_OBSERVATIONS = ("radar", "offset", "occultation")
"""ADES observation elements that are not optical astrometry: counted and said, not read."""


def _records(path, text: str) -> tuple[list[tuple[int, dict]], dict[str, int]]:
    """(line, {field: (text, line)}) of every <optical> element, and the count of every other
    ADES observation element (:data:`OTHER_OBSERVATIONS`) by name."""
    parser = expat.ParserCreate()
    collector = _OpticalCollector(path, parser)
    parser.StartElementHandler = collector.start
    parser.EndElementHandler = collector.end
    parser.CharacterDataHandler = collector.chars
    parser.StartDoctypeDeclHandler = collector.no_entities
    parser.EntityDeclHandler = collector.no_entities
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        raise FieldError(path, exc.lineno, "(XML)", f"not well-formed XML: {expat.ErrorString(exc.code)}") from None
    return collector.out, collector.skipped


class AdesXmlReader(AdesReader):
    """IAU ADES optical astrometry (RA/Dec), XML.

    Parameters
    ----------
    sigma_arcsec : float
        Sigma on the sky (arcsec: on RA x cos(Dec), like rmsRA, and on Dec) for observations
        without rmsRA / rmsDec.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC list (as for ades-psv).
    check_degrees : bool
        Refuse angles that read as radians, as for ades-psv; false reads them as degrees.
    sigma_from_file : bool
        Rows that state rmsRA / rmsDec keep them (true, the default), as for ades-psv; false:
        every row takes ``sigma_arcsec``.
    """

    suffixes = (".xml",)
    measurement_kinds = ("radec",)

    def read(self, path, epoch) -> MeasurementSet:
        ep = parse_epoch(path, epoch)
        text = "\n".join(read_text_lines(path))
        rows, table = [], {}
        records, skipped = _records(path, text)
        skipped = {f"<{name}>": n for name, n in skipped.items()}
        for line, rec in records:
            if is_radar(rec):
                skipped["mode RAD"] = skipped.get("mode RAD", 0) + 1
                continue
            rows.append(record_to_row(rec, path, line, self._sites, table))
        say_skipped(path, skipped, bool(rows))
        say_tiny_sigmas(path, rows)
        return build_set(path, self.checked_rows(path, rows), ep, table, self.sigma_arcsec,
                         {"format": "ades-xml", **self.sigma_meta()},
                         self.designation)

    def write(self, path, measurements, epoch) -> None:
        ep = parse_epoch(path, epoch)
        recs, need_pos = rows_for_writing(measurements, ep, f"reader 'ades-xml' writing {path}")
        fields = list(WRITE_FIELDS) + (list(POS_FIELDS) if need_pos else [])
        out = ['<?xml version="1.0" encoding="UTF-8"?>', '<ades version="2022">', "  <obsBlock>",
               "    <obsData>"]
        for r in recs:
            out.append("      <optical>")
            out += [f"        <{f}>{_escape(r[f])}</{f}>" for f in fields if f in r]
            out.append("      </optical>")
        out += ["    </obsData>", "  </obsBlock>", "</ades>"]
        Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "ades-xml", AdesXmlReader)
