"""IAU ADES observations in PSV (pipe-separated values): reader ``"ades-psv"`` (suffix .psv).

A PSV file: header lines starting with ``#`` (``# version=2022``, ``# observatory`` blocks) or
``!`` (their keywords), then a line of field names separated by ``|``, then one observation per
line with the same number of ``|``-separated fields (values may be padded with spaces). A new
``#`` block may start a new field-name line; a ``#`` or ``!`` line followed by data rows (a comment
between them) is read past, the rows going on under the field names in force. Fields read and written: see
:mod:`cistrack.plugins.readers.ades_records`. Times round-trip to 1 microsecond, angles and
sigmas bit for bit.
"""
from __future__ import annotations

from pathlib import Path

from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.reader import FieldError, read_text_lines, show_field

from .ades_records import (POS_FIELDS, WRITE_FIELDS, AdesReader, is_radar, record_to_row, rows_for_writing, say_skipped,
                           say_tiny_sigmas)
from .obs_rows import build_set, parse_epoch

__all__ = ["AdesPsvReader"]

_KNOWN_FIELDS_MIN = {"obsTime", "ra", "dec", "stn"}


ADES_VERSIONS = ("2017", "2022")
"""The ADES versions whose PSV files this reader reads (their optical fields are the same)."""


def _check_version(path, line: int, text: str) -> None:
    """FieldError for a ``# version=X`` line naming a version other than :data:`ADES_VERSIONS`."""
    key, sep, value = text.lstrip("#!").strip().partition("=")
    if sep and key.strip() == "version" and value.strip() not in ADES_VERSIONS:
        raise FieldError(path, line, "version", f"{show_field(value.strip())}: ADES versions "
                                                f"{' and '.join(ADES_VERSIONS)} are read")


_HEADER_WORDS = _KNOWN_FIELDS_MIN | {"permID", "provID", "artSat", "trkSub", "mode", "rmsRA", "rmsDec", "astCat"}
"""Field names of which one, among a line's cells, makes it a field-name line (no value is one)."""


def _names_fields(cells: list[str]) -> bool:
    """Whether a line after a ``#``/``!`` block is a new field-name line rather than a data row that
    goes on under the header in force (a comment between data rows)."""
    return any(c in _HEADER_WORDS for c in cells)


class AdesPsvReader(AdesReader):
    """IAU ADES optical astrometry (RA/Dec), pipe-separated.

    Parameters
    ----------
    sigma_arcsec : float
        Sigma on the sky (arcsec: on RA x cos(Dec), like rmsRA, and on Dec) for observations
        without rmsRA / rmsDec.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC list: CODE ->
        {latitude_deg, longitude_deg, height_m[, name]} or {longitude_deg, rho_cos_phi,
        rho_sin_phi[, name]}.
    check_degrees : bool
        Refuse a file whose every ra lies in [0, 6.2832] and dec in [-1.5708, 1.5708], or one
        site's rows all so while the object's other rows are not (radians, where ADES has
        degrees); false reads it as degrees.
    sigma_from_file : bool
        true (default): rows that state rmsRA / rmsDec keep them; false: every row takes
        ``sigma_arcsec`` instead (a file whose stated uncertainties are wrong).
    """

    suffixes = (".psv",)
    measurement_kinds = ("radec",)

    def read(self, path, epoch) -> MeasurementSet:
        ep = parse_epoch(path, epoch)
        lines = read_text_lines(path)
        header: list[str] | None = None
        header_line, after_block = 0, False
        rows, table, radar = [], {}, 0
        for i, raw in enumerate(lines, start=1):
            text = raw.strip()
            if not text:
                continue
            if text.startswith("#") or text.startswith("!"):
                _check_version(path, i, text)
                after_block = True  # a new block may bring a new field-name line
                continue
            cells = [c.strip() for c in text.split("|")]
            if header is None or (after_block and _names_fields(cells)):
                missing = sorted(_KNOWN_FIELDS_MIN - set(cells))
                if missing:
                    raise FieldError(path, i, missing[0], f"the field-name line lacks {', '.join(missing)} "
                                                          f"(an ADES PSV header names obsTime, ra, dec, stn)")
                dup = sorted({c for c in cells if cells.count(c) > 1})
                if dup:
                    raise FieldError(path, i, dup[0], "field named twice in the header")
                header, header_line, after_block = cells, i, False
                continue
            after_block = False  # a comment between data rows (probe I7): the rows go on under the same header
            if len(cells) != len(header):
                raise FieldError(path, i, "(field count)", f"{len(cells)} fields, the header of line "
                                                            f"{header_line} has {len(header)}")
            rec = {name: (cell, i) for name, cell in zip(header, cells)}
            if is_radar(rec):
                radar += 1
                continue
            rows.append(record_to_row(rec, path, i, self._sites, table))
        if header is None and not rows and not radar:
            raise FieldError(path, max(1, len(lines)), "(header)", "no ADES PSV field-name line "
                                                                  "(obsTime|ra|dec|stn|...) found")
        say_skipped(path, {"mode RAD": radar} if radar else {}, bool(rows))
        say_tiny_sigmas(path, rows)
        return build_set(path, self.checked_rows(path, rows), ep, table, self.sigma_arcsec,
                         {"format": "ades-psv", **self.sigma_meta()},
                         self.designation)

    def write(self, path, measurements, epoch) -> None:
        who = f"reader 'ades-psv' writing {path}"
        ep = parse_epoch(path, epoch)
        recs, need_pos = rows_for_writing(measurements, ep, who)
        fields = list(WRITE_FIELDS) + (list(POS_FIELDS) if need_pos else [])
        for r in recs:
            if any("|" in v or "\n" in v for v in r.values()):
                raise MeasurementError(f"{who}: a station or object name contains '|' or a newline")
        out = ["# version=2022", "|".join(fields)]
        for r in recs:
            out.append("|".join(r.get(f, "") for f in fields))
        Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "ades-psv", AdesPsvReader)
