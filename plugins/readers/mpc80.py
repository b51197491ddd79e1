"""MPC 80-column optical observations: reader ``"mpc80"`` (suffixes .obs, .mpc, .80col).

One observation per 80-column line (columns counted from 1):

=======  ===============================================================================
1-5      packed minor-planet number (or blank): the designation when given
6-12     provisional or temporary designation: the designation of a line without a number; on a
         line with one it links the lines that give it alone to that number (as an ADES provID
         beside a permID). Packed numbers and provisional designations are read in the form ADES
         files give them ("00433" as 433, "K26F01A" as 2026 FA1: :mod:`.mpc_designations`), so
         that one object given in both formats is one object
13       discovery asterisk
14       note 1
15       note 2: observation type. Optical types are read (blank, C, B, P, T, A, ...);
         two-line observations (S/s satellite, V/v roving, R/r radar, X/x) are refused
16-32    UTC date: ``YYYY MM DD.dddddd`` (fraction of day, 0.0864 s per unit of the 6th decimal)
33-44    RA (topocentric astrometric): ``HH MM SS.sss``
45-56    Dec: ``sDD MM SS.ss``
66-71    magnitude and band (ignored)
78-80    MPC observatory code (bundled table, or the reader's ``sites`` parameter)
=======  ===============================================================================

The format has no uncertainties: every observation gets the reader's ``sigma_arcsec`` (default
1.0 arcsec) on the sky, i.e. on RA x cos(Dec) (sigma_arcsec / cos(Dec) on RA) and on Dec. Lines
that are blank or start with ``#`` (not part of the format) are skipped, and so are the lines of
an MPC submission header (``COD 568``, ``OBS ...``, ``MEA``, ``TEL``, ``NET``, ``ACK``, ``AC2``,
``CON``, ``COM``, ``BND``, ``NUM``: a keyword of three characters, then a space), which carry no
observation. Spaces after column 80 (a line copied from a web page) are read past. The writer writes the
time to 1e-6 day, RA to 0.001 s and Dec to 0.01 arcsec; reading gives those rounded values
back, and writing them again gives the same text. It writes the designation (``meta["object"]``,
else cis0001) in columns 6-12, a provisional designation packed ("2026 FA1" as K26F01A), and
refuses one that does not fit them (over 7 characters) or is blank.
"""
from __future__ import annotations

import math
from datetime import datetime, timedelta, timezone
from decimal import ROUND_HALF_EVEN, Decimal
from pathlib import Path

from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.reader import FieldError, read_text_lines, show_field
from cistrack.units import ARCSEC_RAD, tu_to_utc

from .decimal_units import decimal_in, to_rad
from .mpc_designations import pack_provisional, unpack_number, unpack_provisional
from .obs_rows import ObsRow, build_set, parse_epoch
from .site_params import SiteReader, resolve_site

__all__ = ["Mpc80Reader"]

_OPTICAL = set(" CBPTAeMEOHNnc")
_TWO_LINE = {"S": "satellite", "s": "satellite", "V": "roving observer", "v": "roving observer",
             "R": "radar", "r": "radar", "X": "replaced", "x": "deleted"}


def _digits(text: str, path, line: int, fieldname: str, width: int) -> int:
    if len(text) != width or not text.isdigit():
        raise FieldError(path, line, fieldname, f"{show_field(text)} must be {width} digits")
    return int(text)


def _seconds(text: str, path, line: int, fieldname: str) -> Decimal:
    t = text.strip()
    if not t or not all(c.isdigit() or c == "." for c in t) or t.count(".") > 1:
        raise FieldError(path, line, fieldname, f"{show_field(text)} is not a number of seconds")
    return Decimal(t)


HEADER_KEYWORDS = ("COD", "CON", "OBS", "MEA", "TEL", "NET", "BND", "COM", "NUM", "ACK", "AC2")
"""Keywords of the header of an MPC submission (``COD 568``, ``OBS J. Smith``, ...): lines that
start with one and a space (or are the keyword alone) carry no observation and are skipped."""


def is_header_line(text: str) -> bool:
    """Whether ``text`` is a line of an MPC submission header (:data:`HEADER_KEYWORDS`)."""
    return text[:3] in HEADER_KEYWORDS and text[3:4] in ("", " ")


def _check_line(s: str, path, ln: int) -> None:
    """Length 80, an optical observation type (note 2, column 15), a designation."""
    if len(s) != 80:
        raise FieldError(path, ln, "(line length)", f"{len(s)} characters; an MPC observation line has 80")
    note2 = s[14]
    if note2 in _TWO_LINE:
        raise FieldError(path, ln, "note 2 (column 15)", f"{note2!r}: {_TWO_LINE[note2]} observations (two-line "
                                                          f"records) are not read; optical types are")
    if note2 not in _OPTICAL:
        raise FieldError(path, ln, "note 2 (column 15)", f"{note2!r} is not an MPC observation type")
    if not s[0:12].strip():
        raise FieldError(path, ln, "designation (columns 1-12)", "blank: the observation names no object")


def _date(date: str, path, ln: int) -> datetime:
    """UTC time of columns 16-32 ('YYYY MM DD.dddddd'), rounded to the microsecond."""
    y, mo, d = date[0:4], date[5:7], date[8:]
    if date[4] != " " or date[7] != " ":
        raise FieldError(path, ln, "date (columns 16-32)", f"{show_field(date)} is not 'YYYY MM DD.dddddd'")
    year = _digits(y, path, ln, "date year (columns 16-19)", 4)
    month = _digits(mo, path, ln, "date month (columns 21-22)", 2)
    try:
        day = Decimal(d.strip())
        if not d.strip()[:2].isdigit() or "_" in d or not day.is_finite():
            raise ValueError
    except Exception:
        raise FieldError(path, ln, "date day (columns 24-32)", f"{show_field(d)} is not a day with a decimal fraction") from None
    try:
        base = datetime(year, month, int(day), tzinfo=timezone.utc)
    except ValueError as exc:
        raise FieldError(path, ln, "date (columns 16-32)", f"{show_field(date)}: {exc}") from None
    micro = ((day - int(day)) * Decimal(86_400_000_000)).to_integral_value(ROUND_HALF_EVEN)
    return base + timedelta(microseconds=int(micro))


def _ra(ra_t: str, path, ln: int) -> float:
    """Right ascension (rad) of columns 33-44 ('HH MM SS.sss')."""
    if ra_t[2] != " " or ra_t[5] != " ":
        raise FieldError(path, ln, "RA (columns 33-44)", f"{show_field(ra_t)} is not 'HH MM SS.sss'")
    hh = _digits(ra_t[0:2], path, ln, "RA hours (columns 33-34)", 2)
    mm = _digits(ra_t[3:5], path, ln, "RA minutes (columns 36-37)", 2)
    ss = _seconds(ra_t[6:], path, ln, "RA seconds (columns 39-44)")
    if hh >= 24 or mm >= 60 or ss >= 60:
        raise FieldError(path, ln, "RA (columns 33-44)", f"{show_field(ra_t)} is outside 00 00 00 - 23 59 59.999")
    return to_rad(str((hh * 3600 + mm * 60) * 15 + ss * 15), "arcsec")


def _dec(dec_t: str, path, ln: int) -> float:
    """Declination (rad) of columns 45-56 ('sDD MM SS.ss')."""
    sign = dec_t[0]
    if sign not in "+-" or dec_t[3] != " " or dec_t[6] != " ":
        raise FieldError(path, ln, "Dec (columns 45-56)", f"{show_field(dec_t)} is not 'sDD MM SS.ss'")
    dd = _digits(dec_t[1:3], path, ln, "Dec degrees (columns 46-47)", 2)
    dm = _digits(dec_t[4:6], path, ln, "Dec minutes (columns 49-50)", 2)
    ds = _seconds(dec_t[7:], path, ln, "Dec seconds (columns 52-56)")
    if dm >= 60 or ds >= 60 or dd > 90 or (dd == 90 and (dm or ds)):
        raise FieldError(path, ln, "Dec (columns 45-56)", f"{show_field(dec_t)} is outside -90 00 00 - +90 00 00")
    dec_abs = to_rad(str(dd * 3600 + dm * 60 + ds), "arcsec")
    return -dec_abs if sign == "-" else dec_abs


def _site_code(code: str, path, ln: int, explicit, table) -> str:
    """The observatory code of columns 78-80, its site entered in ``table``."""
    if not code.strip() or " " in code:
        raise FieldError(path, ln, "observatory code (columns 78-80)", f"{show_field(code)} is not a 3-character code")
    if code not in table:
        try:
            table[code] = resolve_site(code, explicit)
        except MeasurementError as exc:
            raise FieldError(path, ln, "observatory code (columns 78-80)", str(exc)) from None
    return code


def _parse(line_text: str, path, ln: int, explicit, table) -> ObsRow:
    s = line_text[:80] + line_text[80:].rstrip()  # spaces after column 80 (a copy from a web page) are not part of it
    _check_line(s, path, ln)
    t = _date(s[15:32], path, ln)
    ra = _ra(s[32:44], path, ln)
    dec = _dec(s[44:56], path, ln)
    code = _site_code(s[77:80], path, ln, explicit, table)
    number, provisional = unpack_number(s[0:5].strip()), unpack_provisional(s[5:12].strip())
    # the number names the object when given (as the MPC does), its provisional designation then links
    # the lines that give that alone; the two fields together are no designation (probe I6); both in
    # the form ADES files give them, so that one object in the two formats is one object (probe N15)
    return ObsRow(t, ra, dec, None, None, code, "radec", ln, "date (columns 16-32)", number or provisional,
                  provisional if number and provisional != number else "")


def _format(t: datetime, ra: float, dec: float, code: str, desig: str) -> str:
    mid = t.replace(hour=0, minute=0, second=0, microsecond=0)
    units_of_day = (Decimal((t - mid) // timedelta(microseconds=1)) / Decimal(86_400)).to_integral_value(ROUND_HALF_EVEN)
    t = mid + timedelta(microseconds=int(units_of_day) * 86_400)  # rounded to 1e-6 day (may roll over)
    mid = t.replace(hour=0, minute=0, second=0, microsecond=0)
    day = Decimal(t.day) + Decimal((t - mid) // timedelta(microseconds=1)) / Decimal(86_400_000_000)
    ra_s = (decimal_in(ra % (2 * math.pi), "arcsec") / 15).quantize(Decimal("0.001"), ROUND_HALF_EVEN)
    ra_s %= 86400
    h, rem = divmod(ra_s, 3600)
    m, sec = divmod(rem, 60)
    dec_s = decimal_in(abs(dec), "arcsec").quantize(Decimal("0.01"), ROUND_HALF_EVEN)
    dd, rem = divmod(dec_s, 3600)
    dm, dsec = divmod(rem, 60)
    sign = "-" if dec < 0 and dec_s > 0 else "+"
    line = (f"{'':5}{desig:<7}  C{t.year:04d} {t.month:02d} {day:09.6f}"
            f"{int(h):02d} {int(m):02d} {sec:06.3f}{sign}{int(dd):02d} {int(dm):02d} {dsec:05.2f}"
            f"{'':21}{code}")
    return line


DESIGNATION_COLUMNS = 7
"""Width of the designation the writer writes: columns 6-12, the provisional or temporary
designation of the MPC format (columns 1-5 hold a packed number, which cistrack does not write)."""


def _designation_problem(desig: str) -> str | None:
    """Why the writer cannot write ``desig`` so that reading gives it back, or None."""
    if not desig.strip():
        return "is blank: an MPC observation must name its object"
    if len(desig) > DESIGNATION_COLUMNS:
        return (f"has {len(desig)} characters; the MPC designation field (columns 6-12) holds "
                f"{DESIGNATION_COLUMNS} (write ADES .psv or .xml, which hold any designation)")
    if desig != desig.strip() or not desig.isprintable():
        return "has spaces at its ends or characters that are not printable"
    return None


DOS_EOF = "\x1a"
"""The end-of-file byte (Ctrl-Z) some DOS-era tools append to a text file; read as its end."""


class Mpc80Reader(SiteReader):
    """MPC 80-column optical astrometry (RA/Dec; no uncertainties in the format).

    Parameters
    ----------
    sigma_arcsec : float
        Sigma of every observation on the sky, arcsec: on RA x cos(Dec) and on Dec.
    sites : dict or None
        Explicit sites for observatory codes outside the bundled MPC list.
    """

    suffixes = (".obs", ".mpc", ".80col")
    measurement_kinds = ("radec",)
    time_resolution_s = 0.0864
    angle_resolution_rad = 0.015 * ARCSEC_RAD
    carries_sigmas = False

    def read(self, path, epoch) -> MeasurementSet:
        ep = parse_epoch(path, epoch)
        rows, table = [], {}
        for i, text in enumerate(read_text_lines(path), start=1):
            text = text.rstrip(DOS_EOF)  # a DOS file's end-of-file byte (Ctrl-Z) ends it, on its own line or the last
            if not text.strip() or text.startswith("#") or is_header_line(text):
                continue
            rows.append(_parse(text, path, i, self._sites, table))
        return build_set(path, rows, ep, table, self.sigma_arcsec, {"format": "mpc80"}, self.designation)

    def write(self, path, measurements, epoch) -> None:
        who = f"reader 'mpc80' writing {path}"
        ep = parse_epoch(path, epoch)
        ms = measurements
        kinds = set(ms.kinds.tolist()) if ms.kinds is not None else {"radec" if ms.names[:2] == ("right_ascension", "declination") else "?"}
        if kinds != {"radec"}:
            raise MeasurementError(f"{who}: MPC 80-column observations are RA/Dec; this set has types {sorted(kinds)}")
        if ms.sites is None:
            raise MeasurementError(f"{who}: the set has no observing sites (MPC codes)")
        bad = sorted({k for k in ms.sites.tolist() if len(k) != 3 or " " in k})
        if bad:
            raise MeasurementError(f"{who}: sites {bad} are not 3-character MPC observatory codes")
        desig = str(ms.meta.get("object", "cis0001"))
        desig = pack_provisional(desig) or desig  # "2026 FA1" is written as the MPC packs it, "K26F01A"
        problem = _designation_problem(desig)
        if problem:
            raise MeasurementError(f"{who}: designation {show_field(desig)} {problem}")
        out = [_format(tu_to_utc(ep, ms.times[k]), float(ms.values[k, 0]), float(ms.values[k, 1]),
                       str(ms.sites[k]), desig) for k in range(len(ms))]
        Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "mpc80", Mpc80Reader)
