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
from cistrack.interfaces.reader import FieldError, read_text_lines

from .ades_records import POS_FIELDS, WRITE_FIELDS, record_to_row, rows_for_writing
from .obs_rows import build_set, parse_epoch
from .site_params import SiteReader

__all__ = ["AdesXmlReader"]


def _escape(text: str) -> str:
    """``&``, ``<`` and ``>`` as XML entities (what xml.sax.saxutils.escape does; that module
    imports urllib.request, ~12 ms of every start-up that lists the readers)."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _records(path, text: str) -> list[tuple[int, dict]]:
    """(line, {field: (text, line)}) of every <optical> element."""
    parser = expat.ParserCreate()
    out: list[tuple[int, dict]] = []
    stack: list[str] = []
    state = {"rec": None, "line": 0, "field": None, "buf": [], "fline": 0, "root": None}

    def start(name, attrs):
        line = parser.CurrentLineNumber
        if state["root"] is None:
            state["root"] = name
            if name != "ades":
                raise FieldError(path, line, "<ades>", f"the root element is <{name[:40]}>, not <ades>")
        stack.append(name)
        if name == "optical":
            if state["rec"] is not None:
                raise FieldError(path, line, "<optical>", "an <optical> element inside another")
            state["rec"], state["line"] = {}, line
        elif state["rec"] is not None:
            if state["field"] is not None:
                raise FieldError(path, line, state["field"], f"contains an element <{name[:40]}>; ADES fields are text")
            state["field"], state["buf"], state["fline"] = name, [], line

    def end(name):
        stack.pop()
        if name == "optical":
            out.append((state["line"], state["rec"]))
            state["rec"] = None
        elif state["rec"] is not None and state["field"] == name:
            if name in state["rec"]:
                raise FieldError(path, state["fline"], name, "field given twice in one observation")
            state["rec"][name] = ("".join(state["buf"]), state["fline"])
            state["field"] = None

    def chars(data):
        if state["field"] is not None:
            state["buf"].append(data)

    def no_entities(*_args):
        raise FieldError(path, parser.CurrentLineNumber, "(DOCTYPE)", "DTDs and entity declarations are not allowed")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = no_entities
    parser.EntityDeclHandler = no_entities
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        raise FieldError(path, exc.lineno, "(XML)", f"not well-formed XML: {expat.ErrorString(exc.code)}") from None
    return out


class AdesXmlReader(SiteReader):
    """IAU ADES optical astrometry (RA/Dec), XML.

    Parameters
    ----------
    sigma_arcsec : float
        Sigma on the sky (arcsec: on RA x cos(Dec), like rmsRA, and on Dec) for observations
        without rmsRA / rmsDec.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC list (as for ades-psv).
    """

    suffixes = (".xml",)
    measurement_kinds = ("radec",)

    def read(self, path, epoch) -> MeasurementSet:
        ep = parse_epoch(path, epoch)
        text = "\n".join(read_text_lines(path))
        rows, table = [], {}
        for line, rec in _records(path, text):
            rows.append(record_to_row(rec, path, line, self._sites, table))
        return build_set(path, rows, ep, table, self.sigma_arcsec, {"format": "ades-xml"}, self.designation)

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
