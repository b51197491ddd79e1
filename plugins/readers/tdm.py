"""CCSDS Tracking Data Messages (TDM, KVN syntax) of angles: reader ``"tdm"`` (suffix .tdm).

Read: a header (``CCSDS_TDM_VERS``, ``CREATION_DATE``, ``ORIGINATOR``), then segments of
``META_START`` ... ``META_STOP`` and ``DATA_START`` ... ``DATA_STOP``. Per segment:

* ``TIME_SYSTEM = UTC`` (others are refused);
* ``PARTICIPANT_1`` the observing station: an MPC observatory code of the bundled table, a key
  of the reader's ``sites`` parameter, or a site declared in the segment by a comment line
  ``COMMENT cistrack site KEY latitude_deg=.. longitude_deg=.. height_m=..`` (what the writer
  writes for sites that are not MPC codes); ``PARTICIPANT_2`` the object (a segment without it is
  of the one object the other segments name; beside several it is refused);
* ``MODE = SEQUENTIAL`` and ``PATH`` between participants 1 and 2 (``2,1``), when given (others
  are refused: the angles are read as the station observing the object);
* ``ANGLE_TYPE = AZEL`` (ANGLE_1 azimuth, ANGLE_2 elevation) or ``RADEC`` (right ascension,
  declination; ``REFERENCE_FRAME`` EME2000, ICRF or GCRF); angles in degrees;
* ``DATA_QUALITY`` (when given) ``RAW`` or ``VALIDATED``; ``DEGRADED`` data are read with a warning
  (logger ``cistrack.readers``) naming the file; any other value (``REJECTED``, ...) refuses the
  file, naming the keyword and its line, whatever other segments it holds;
* ``TIMETAG_REF`` (when given) ``RECEIVE``, the time the light reached the station (``TRANSMIT``
  means nothing for optical angles and is refused);
* ``INTEGRATION_INTERVAL`` (seconds, at most a day) with ``INTEGRATION_REF``: the observation's
  time is the middle of the exposure, so a time tag at its ``START`` is moved on by half the
  interval and one at its ``END`` back by half; ``MIDDLE`` (the default) moves nothing. ``START``
  or ``END`` without an interval is refused;
* data lines ``ANGLE_1 = <epoch> <value>`` and ``ANGLE_2 = <epoch> <value>``, one pair per
  observation at the same epoch (``YYYY-MM-DDThh:mm:ss[.d...]`` or ``YYYY-DDDThh:mm:ss[.d...]``).

TDM has no per-observation uncertainty: the reader's ``sigma_arcsec`` (default 1.0 arcsec, on
the sky: RA x cos(Dec) and Dec) applies unless the segment has ``COMMENT cistrack sigma_arcsec
ANGLE_1=.. ANGLE_2=..`` (arcsec; for RADEC ANGLE_1 is on RA x cos(Dec)), which the writer writes
(one segment per run of measurements with the same site, type and sigmas). Other keywords
(RANGE, DOPPLER, ...) are refused by name. A file whose every ANGLE_1 lies in [0, 2 pi] and
every ANGLE_2 in [-pi/2, pi/2], or in which one site's rows all do while the object's other rows
do not, is refused as angles written in radians (the parameter
``check_degrees = false`` reads it as degrees). Times round-trip to 1 microsecond, angles and sigmas
bit for bit.
"""
from __future__ import annotations

import math
import re
import logging
from datetime import datetime, timedelta, timezone
from decimal import Decimal
from pathlib import Path

from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.component import sigma_arcsec_problem
from cistrack.interfaces.reader import FieldError, read_text_lines, show_field
from cistrack.astro.sites import Site, observatory
from cistrack.units import format_utc, tu_to_utc

from .ades_records import SMALLEST_PLAUSIBLE_ARCSEC
from .decimal_units import from_rad, plain_float, to_rad
from .obs_rows import ObsRow, build_set, parse_epoch
from .site_params import DegreesCheckedReader, resolve_site

__all__ = ["TdmReader"]

_HEADER_KEYS = {"CCSDS_TDM_VERS", "CREATION_DATE", "ORIGINATOR", "MESSAGE_ID"}
_META_KEYS = {"TIME_SYSTEM", "PARTICIPANT_1", "PARTICIPANT_2", "PARTICIPANT_3", "PARTICIPANT_4", "PARTICIPANT_5",
              "MODE", "PATH", "PATH_1", "PATH_2", "ANGLE_TYPE", "REFERENCE_FRAME", "START_TIME", "STOP_TIME",
              "TRANSMIT_BAND", "RECEIVE_BAND", "INTEGRATION_INTERVAL", "INTEGRATION_REF", "DATA_QUALITY",
              "TIMETAG_REF", "CORRECTIONS_APPLIED", "EPHEMERIS_NAME_1", "EPHEMERIS_NAME_2", "TRACK_ID",
              "RANGE_MODE", "RANGE_MODULUS", "RANGE_UNITS", "INTERPOLATION", "INTERPOLATION_DEGREE"}
_RADEC_FRAMES = {"EME2000", "ICRF", "GCRF"}
_QUALITIES = ("RAW", "VALIDATED", "DEGRADED")
MAX_INTEGRATION_S = 86_400.0
"""The longest INTEGRATION_INTERVAL read, seconds (an optical exposure is far shorter)."""
_TIME_RE = re.compile(r"^(\d{4})-(?:(\d{2})-(\d{2})|(\d{3}))T(\d{2}):(\d{2}):(\d{2})(\.\d+)?Z?$")
_SITE_RE = re.compile(r"^cistrack site (\S+) latitude_deg=(\S+) longitude_deg=(\S+) height_m=(\S+)$")
_SIGMA_RE = re.compile(r"^cistrack sigma_arcsec ANGLE_1=(\S+) ANGLE_2=(\S+)$")


def _parse_time(text: str) -> datetime:
    m = _TIME_RE.match(text)
    if not m:
        raise ValueError("is not a CCSDS time (YYYY-MM-DDThh:mm:ss.d or YYYY-DDDThh:mm:ss.d)")
    year = int(m.group(1))
    if m.group(4):
        base = datetime(year, 1, 1, tzinfo=timezone.utc) + timedelta(days=int(m.group(4)) - 1)
        if base.year != year or int(m.group(4)) < 1:
            raise ValueError("has a day of year outside the year")
    else:
        base = datetime(year, int(m.group(2)), int(m.group(3)), tzinfo=timezone.utc)
    hh, mm, ss = int(m.group(5)), int(m.group(6)), int(m.group(7))
    if hh > 23 or mm > 59 or ss > 59:
        raise ValueError("has hours, minutes or seconds out of range (leap second 60 not supported)")
    frac = m.group(8) or ""
    micro = round(float("0" + frac) * 1e6) if frac else 0
    return base + timedelta(hours=hh, minutes=mm, seconds=ss, microseconds=micro)


def _kv(text: str, path, ln: int) -> tuple[str, str]:
    if "=" not in text:
        raise FieldError(path, ln, "(keyword)", f"{show_field(text.split()[0] if text.split() else text)} is not "
                                                f"'KEYWORD = value'")
    k, v = text.split("=", 1)
    return k.strip(), v.strip()


class _Segment:
    def __init__(self, line: int):
        self.line = line
        self.meta: dict[str, tuple[str, int]] = {}
        self.comments: list[tuple[str, int]] = []


def _first_sigma(ctx: dict, dec: float) -> float | None:
    """ANGLE_1's sigma (rad) of an observation in a segment with a cistrack sigma comment: for
    RADEC the comment's value is on the sky (RA x cos(Dec)), so it is divided by cos(Dec)."""
    if ctx["sig"][0] is None or ctx["kind"] != "radec":
        return ctx["sig"][0]
    return to_rad(ctx["sig_text"], "arcsec", math.cos(dec))


def _sigma_texts(ms, k: int, kind: str) -> tuple[str, str]:
    """The sigma comment's texts (arcsec) of measurement k: ANGLE_1 on the sky for RADEC."""
    scale = math.cos(float(ms.values[k, 1])) if kind == "radec" else 1.0
    return from_rad(float(ms.sigmas[k, 0]), "arcsec", scale=scale), from_rad(float(ms.sigmas[k, 1]), "arcsec")


def _reads_back(texts: tuple[str, str], ms, k: int, kind: str) -> bool:
    """Whether a segment whose sigma comment says ``texts`` reads measurement k's sigmas exactly."""
    scale = math.cos(float(ms.values[k, 1])) if kind == "radec" else 1.0
    return (to_rad(texts[0], "arcsec", scale) == float(ms.sigmas[k, 0])
            and to_rad(texts[1], "arcsec") == float(ms.sigmas[k, 1]))


def _check_angle(path, ln: int, k: str, text: str, val: float) -> None:
    """Refuse an ANGLE_1 outside [0, 2 pi) or an ANGLE_2 outside [-pi/2, pi/2] (``val`` in rad)."""
    if k == "ANGLE_1" and not 0.0 <= val < 2.0 * math.pi:
        raise FieldError(path, ln, f"{k} value", f"{show_field(text)} is outside [0, 360) degrees")
    if k == "ANGLE_2" and not -0.5 * math.pi <= val <= 0.5 * math.pi:
        raise FieldError(path, ln, f"{k} value", f"{show_field(text)} is outside [-90, 90] degrees")


def _segment_kind(path, seg: _Segment, ln: int) -> str:
    """The segment's measurement kind, "azel" or "radec", after checking its required metadata."""
    meta = seg.meta
    for key in ("TIME_SYSTEM", "PARTICIPANT_1", "ANGLE_TYPE"):
        if key not in meta:
            raise FieldError(path, ln, key, f"missing from the metadata block starting at line {seg.line}")
    ts, tl = meta["TIME_SYSTEM"]
    if ts != "UTC":
        raise FieldError(path, tl, "TIME_SYSTEM", f"{show_field(ts)}: only UTC is read")
    at, al = meta["ANGLE_TYPE"]
    if at not in ("AZEL", "RADEC"):
        raise FieldError(path, al, "ANGLE_TYPE", f"{show_field(at)}: AZEL and RADEC are read")
    _check_mode_and_path(path, meta)
    _check_quality_and_timetag(path, meta, seg.line)
    kind = at.lower()
    rf, rl = meta.get("REFERENCE_FRAME", ("", ln))
    if kind == "radec" and rf not in _RADEC_FRAMES:
        raise FieldError(path, rl, "REFERENCE_FRAME", f"{show_field(rf)}: RADEC angles need one of "
                                                      f"{', '.join(sorted(_RADEC_FRAMES))}")
    return kind


def _check_quality_and_timetag(path, meta: dict, first: int) -> None:
    """Refuse a DATA_QUALITY other than RAW, VALIDATED or DEGRADED and a TIMETAG_REF other than
    RECEIVE (both optional); ``first`` is the line of the segment's META_START."""
    quality, ql = meta.get("DATA_QUALITY", ("RAW", 0))
    if quality not in _QUALITIES:
        raise FieldError(path, ql, "DATA_QUALITY", f"{show_field(quality)}: the data of the segment starting at line "
                                                   f"{first} are not to be used; RAW and VALIDATED data are read, "
                                                   "DEGRADED with a warning (leave the segment out of the file)")
    ref, rl = meta.get("TIMETAG_REF", ("RECEIVE", 0))
    if ref != "RECEIVE":
        raise FieldError(path, rl, "TIMETAG_REF", f"{show_field(ref)}: optical angles are tagged with the time the "
                                                  "light was received (TIMETAG_REF = RECEIVE, the default)")


def _integration_shift(path, meta: dict) -> timedelta:
    """What moves a data line's time tag to the middle of its exposure: half INTEGRATION_INTERVAL
    on for INTEGRATION_REF = START, back for END; nothing for MIDDLE (the default)."""
    ref, rl = meta.get("INTEGRATION_REF", ("MIDDLE", 0))
    if ref not in ("START", "MIDDLE", "END"):
        raise FieldError(path, rl, "INTEGRATION_REF", f"{show_field(ref)}: START, MIDDLE or END")
    if "INTEGRATION_INTERVAL" not in meta:
        if ref != "MIDDLE":
            raise FieldError(path, rl, "INTEGRATION_REF", f"{ref} needs INTEGRATION_INTERVAL (seconds) to place the "
                                                          "middle of the exposure")
        return timedelta(0)
    text, il = meta["INTEGRATION_INTERVAL"]
    try:
        seconds = plain_float(text)
    except ValueError:
        seconds = math.nan
    if not 0.0 < seconds <= MAX_INTEGRATION_S:
        raise FieldError(path, il, "INTEGRATION_INTERVAL", f"{show_field(text)}: must be a number of seconds in "
                                                           f"(0, {MAX_INTEGRATION_S:.0f}]")
    half = timedelta(microseconds=int(round(Decimal(text) * 500_000)))
    return {"START": half, "MIDDLE": timedelta(0), "END": -half}[ref]


def _check_mode_and_path(path, meta: dict) -> None:
    """Refuse a MODE other than SEQUENTIAL and a PATH other than one between PARTICIPANT_1 (the
    station) and PARTICIPANT_2 (the object), the geometry the angles are read with (both optional)."""
    mode, ml = meta.get("MODE", ("SEQUENTIAL", 0))
    if mode != "SEQUENTIAL":
        raise FieldError(path, ml, "MODE", f"{show_field(mode)}: angles are read in MODE = SEQUENTIAL only")
    if "PATH" not in meta:
        return
    text, pl = meta["PATH"]
    legs = [leg.strip() for leg in text.split(",")]
    if len(legs) < 2 or set(legs) != {"1", "2"}:
        raise FieldError(path, pl, "PATH", f"{show_field(text)}: the angles are read as PARTICIPANT_1 (the station) "
                                           "observing PARTICIPANT_2 (the object): give PATH = 2,1 (or 1,2)")


def _declared_site(path, m: re.Match, cl: int) -> Site:
    """The site of a ``COMMENT cistrack site KEY latitude_deg=.. longitude_deg=.. height_m=..``."""
    try:
        lat, lon, height = (plain_float(m.group(i)) for i in (2, 3, 4))
        return Site(lat, lon, height, name=m.group(1))
    except (ValueError, MeasurementError) as exc:
        raise FieldError(path, cl, "COMMENT cistrack site", str(exc)[:120]) from None


def _comment_sigmas(path, m: re.Match, cl: int) -> tuple[tuple[float, float], str]:
    """The (ANGLE_1, ANGLE_2) sigmas (rad) of a ``COMMENT cistrack sigma_arcsec ..`` and ANGLE_1's text."""
    try:
        sig = (to_rad(m.group(1), "arcsec"), to_rad(m.group(2), "arcsec"))
    except ValueError:
        raise FieldError(path, cl, "COMMENT cistrack sigma_arcsec", "the sigmas are not numbers") from None
    problem = next(filter(None, (sigma_arcsec_problem(float(t)) for t in m.groups())), None)
    if problem:
        raise FieldError(path, cl, "COMMENT cistrack sigma_arcsec", f"the sigmas {problem}")
    return sig, m.group(1)


def _tiny_comment_sigma(seg: _Segment) -> tuple[int, float] | None:
    """(line, arcsec) of the first sigma below :data:`SMALLEST_PLAUSIBLE_ARCSEC` in the segment's
    ``COMMENT cistrack sigma_arcsec``, or None."""
    for text, cl in seg.comments:
        m = _SIGMA_RE.match(text)
        tiny = [float(t) for t in m.groups() if float(t) < SMALLEST_PLAUSIBLE_ARCSEC] if m else []
        if tiny:
            return cl, tiny[0]
    return None


def _say_tiny_sigmas(path, tiny: list[tuple[int, float]]) -> None:
    """Warn (logger ``cistrack.readers``, once per file) of sigma comments below 1 milliarcsecond:
    arcseconds by the comment's name, most likely degrees by mistake. They are used as given."""
    if tiny:
        logging.getLogger("cistrack.readers").warning(
            f"{path}, line {tiny[0][0]}: COMMENT cistrack sigma_arcsec: {len(tiny)} segments state an uncertainty "
            f"below 1 milliarcsecond (this one {tiny[0][1]:.3g} arcsec); the comment is in arcseconds: are these "
            "degrees? They are used as given")


def _segment_comments(path, seg: _Segment) -> tuple[dict[str, Site], tuple, str]:
    """Sites declared in the segment's cistrack comments, and its sigmas (rad; (None, None) when
    absent) with ANGLE_1's sigma text."""
    declared: dict[str, Site] = {}
    sig, sig_text = (None, None), ""
    seen: dict[str, int] = {}  # what each comment declares -> its line
    for text, cl in seg.comments:
        m = _SITE_RE.match(text) or _SIGMA_RE.match(text)
        if m:
            what = f"cistrack site {m.group(1)}" if m.re is _SITE_RE else "cistrack sigma_arcsec"
            if what in seen:
                raise FieldError(path, cl, f"COMMENT {what}", f"given again: line {seen[what]} of this metadata "
                                 f"block (from line {seg.line}) gives it already; each is given once")
            seen[what] = cl
        if m and m.re is _SITE_RE:
            declared[m.group(1)] = _declared_site(path, m, cl)
        elif m:
            sig, sig_text = _comment_sigmas(path, m, cl)
        elif text.split()[:1] == ["cistrack"]:
            raise FieldError(path, cl, "COMMENT cistrack", f"{show_field(text[:60])} is not one this reader knows: "
                             "'cistrack site KEY latitude_deg=.. longitude_deg=.. height_m=..' or 'cistrack "
                             "sigma_arcsec ANGLE_1=.. ANGLE_2=..'")
    return declared, sig, sig_text


def _participant_site(path, seg: _Segment, declared: dict, table: dict, sites: dict) -> str:
    """PARTICIPANT_1's name, its site entered in ``table`` (declared in the segment, else a key of
    ``sites`` or an MPC code)."""
    name, nl = seg.meta["PARTICIPANT_1"]
    if name in declared:
        site = declared[name]
    else:
        try:
            site = resolve_site(name, sites)
        except MeasurementError as exc:
            raise FieldError(path, nl, "PARTICIPANT_1", str(exc)) from None
    if name in table and table[name] != site:
        raise FieldError(path, nl, "PARTICIPANT_1", f"{show_field(name)} was declared with another position earlier")
    table[name] = site
    return name


def _segment_span(path, seg: _Segment) -> tuple[datetime, datetime] | None:
    """The segment's (START_TIME, STOP_TIME) when it gives both (its data must lie within them),
    else None; FieldError for a time that cannot be read or a STOP_TIME before the START_TIME."""
    if "START_TIME" not in seg.meta or "STOP_TIME" not in seg.meta:
        return None
    times = []
    for key in ("START_TIME", "STOP_TIME"):
        text, kl = seg.meta[key]
        try:
            times.append(_parse_time(text))
        except ValueError as exc:
            raise FieldError(path, kl, key, f"{show_field(text)} {exc}") from None
    if times[1] < times[0]:
        raise FieldError(path, seg.meta["STOP_TIME"][1], "STOP_TIME", "is before START_TIME")
    return times[0], times[1]


def _segment_context(path, seg: _Segment, ln: int, table: dict, sites: dict) -> dict:
    """What the data lines of a segment need: kind, site name, sigmas, object (PARTICIPANT_2)."""
    kind = _segment_kind(path, seg, ln)
    declared, sig, sig_text = _segment_comments(path, seg)
    name = _participant_site(path, seg, declared, table, sites)
    return {"kind": kind, "site": name, "sig": sig, "sig_text": sig_text,
            "object": seg.meta.get("PARTICIPANT_2", ("", ln))[0], "shift": _integration_shift(path, seg.meta),
            "degraded": seg.meta.get("DATA_QUALITY", ("", 0))[0] == "DEGRADED",
            "frame_ignored": seg.meta["REFERENCE_FRAME"] if kind == "azel" and "REFERENCE_FRAME" in seg.meta else None}


class _TdmParse:
    """One pass over a TDM file's lines, block by block (header, then META and DATA segments):
    collects the observations as :class:`ObsRow` (angles in rad) and the sites by name."""

    _ENDS = {"header": "META_START", "meta": "META_STOP", "between": "DATA_START", "data": "DATA_STOP"}

    def __init__(self, path, sites: dict) -> None:
        self.path, self.sites = path, sites
        self.state, self.seg = "header", None
        self.seen_version = False
        self.header_lines: dict[str, int] = {}  # header keyword -> its line
        self.rows: list[ObsRow] = []
        self.table: dict[str, Site] = {}
        self.pending: dict[datetime, tuple[str, float, int]] = {}  # epoch -> (keyword, angle, line)
        self.ctx: dict = {}
        self.degraded: list[int] = []  # lines of observations in DATA_QUALITY = DEGRADED segments
        self.frames_ignored: list[tuple[str, int]] = []  # (REFERENCE_FRAME, line) of AZEL segments
        self.tiny_sigmas: list[tuple[int, float]] = []  # (line, arcsec) of sigma comments below 1 mas

    def run(self, lines: list[str]) -> None:
        handlers = {"header": self._header, "meta": self._meta, "between": self._between,
                    "data": self._data, "after": self._after}
        for ln, raw in enumerate(lines, start=1):
            text = raw.strip()
            if not text:
                continue
            word = text.split()[0]
            if word == "COMMENT":
                if self.seg is not None and self.state == "meta":
                    self.seg.comments.append((text[7:].strip(), ln))
                continue
            handlers[self.state](word, text, ln)
        if self.state != "after":
            where = self._ENDS[self.state]
            raise FieldError(self.path, max(1, len(lines)), where, f"the file ends without {where}")

    def _header(self, word: str, text: str, ln: int) -> None:
        if word == "META_START":
            if not self.seen_version:
                raise FieldError(self.path, ln, "CCSDS_TDM_VERS", "the header must start with CCSDS_TDM_VERS")
            self.state, self.seg = "meta", _Segment(ln)
            return
        k, v = _kv(text, self.path, ln)
        if k not in _HEADER_KEYS:
            raise FieldError(self.path, ln, k[:40], f"unknown header keyword; expected {', '.join(sorted(_HEADER_KEYS))} then META_START")
        if k in self.header_lines:
            raise FieldError(self.path, ln, k, f"given again: line {self.header_lines[k]} of the header gives it "
                                               "already; each keyword is given once")
        self.header_lines[k] = ln
        if k == "CCSDS_TDM_VERS":
            if v not in ("1.0", "2.0"):
                raise FieldError(self.path, ln, k, f"{show_field(v)}: versions 1.0 and 2.0 are read")
            self.seen_version = True

    def _meta(self, word: str, text: str, ln: int) -> None:
        if word == "META_STOP":
            self.ctx = _segment_context(self.path, self.seg, ln, self.table, self.sites)
            if self.ctx["frame_ignored"] is not None:
                self.frames_ignored.append(self.ctx["frame_ignored"])
            self.tiny_sigmas += filter(None, [_tiny_comment_sigma(self.seg)])
            self.ctx["span"] = _segment_span(self.path, self.seg)
            self.state = "between"
            return
        k, v = _kv(text, self.path, ln)
        if k not in _META_KEYS:
            raise FieldError(self.path, ln, k[:40], "unknown metadata keyword")
        if k in self.seg.meta:
            raise FieldError(self.path, ln, k, f"given again: line {self.seg.meta[k][1]} of this metadata block "
                                               f"(from line {self.seg.line}) gives it already; each keyword is given "
                                               "once per block")
        self.seg.meta[k] = (v, ln)

    def _between(self, word: str, text: str, ln: int) -> None:
        if word != "DATA_START":
            raise FieldError(self.path, ln, word[:40], "expected DATA_START after META_STOP")
        self.state = "data"

    def _after(self, word: str, text: str, ln: int) -> None:
        if word != "META_START":
            raise FieldError(self.path, ln, word[:40], "expected META_START (a new segment) after DATA_STOP")
        self.state, self.seg = "meta", _Segment(ln)

    def _data(self, word: str, text: str, ln: int) -> None:
        if word == "DATA_STOP":
            if self.pending:
                t0, (name, _v, pl) = next(iter(self.pending.items()))
                other = "ANGLE_2" if name == "ANGLE_1" else "ANGLE_1"
                raise FieldError(self.path, pl, other, f"{name} at {format_utc(t0)} has no {other} at the same epoch")
            self.state, self.seg = "after", None
            return
        k, t, val = self._data_line(text, ln)
        self._pair(k, t, val, ln)

    def _data_line(self, text: str, ln: int) -> tuple[str, datetime, float]:
        """Keyword, epoch and angle (rad) of ``ANGLE_n = <epoch> <value>``."""
        path = self.path
        k, v = _kv(text, path, ln)
        if k not in ("ANGLE_1", "ANGLE_2"):
            raise FieldError(path, ln, k[:40], "only ANGLE_1 and ANGLE_2 data are read")
        parts = v.split()
        if len(parts) != 2:
            raise FieldError(path, ln, k, "expected '<epoch> <value>'")
        try:
            t = _parse_time(parts[0])
        except ValueError as exc:
            raise FieldError(path, ln, f"{k} epoch", f"{show_field(parts[0])} {exc}") from None
        try:
            val = to_rad(parts[1], "deg")
        except ValueError as exc:
            raise FieldError(path, ln, f"{k} value", f"{show_field(parts[1])} is {exc}") from None
        _check_angle(path, ln, k, parts[1], val)
        span = self.ctx.get("span")
        if span is not None and not span[0] <= t <= span[1]:
            raise FieldError(path, ln, f"{k} epoch", f"{format_utc(t)[:23]}Z lies outside the segment's START_TIME "
                                                     f"to STOP_TIME ({format_utc(span[0])[:19]}Z to {format_utc(span[1])[:19]}Z)")
        return k, t, val

    def _pair(self, k: str, t: datetime, val: float, ln: int) -> None:
        """Hold an angle until the other one at its epoch arrives, then add the observation."""
        if t not in self.pending:
            self.pending[t] = (k, val, ln)
            return
        name, other_v, pl = self.pending.pop(t)
        if name == k:
            raise FieldError(self.path, ln, k, f"a second {k} at {format_utc(t)} (line {pl} has the first)")
        a, b = (other_v, val) if name == "ANGLE_1" else (val, other_v)
        ctx = self.ctx
        self.rows.append(ObsRow(t + ctx["shift"], a, b, _first_sigma(ctx, b), ctx["sig"][1], ctx["site"],
                                ctx["kind"], min(ln, pl), "ANGLE_1 epoch", ctx["object"]))
        if ctx["degraded"]:
            self.degraded.append(min(ln, pl))


def _say_frames_ignored(path, frames: list[tuple[str, int]]) -> None:
    """Warn (logger ``cistrack.readers``, once per file) of REFERENCE_FRAME given in AZEL segments."""
    if frames:
        (rf, rl), n = frames[0], len(frames)
        more = f" (and in {n - 1} more AZEL segment(s))" if n > 1 else ""
        logging.getLogger("cistrack.readers").warning(
            f"{path}, line {rl}: REFERENCE_FRAME = {show_field(rf)}{more} applies to RADEC angles; AZEL angles are "
            "read as azimuth and elevation at the site")


def _say_degraded(path, lines: list[int]) -> None:
    """Warn (logger ``cistrack.readers``) that the observations at ``lines`` are DEGRADED data."""
    if lines:
        logging.getLogger("cistrack.readers").warning(
            f"{path}: {len(lines)} observations (from line {min(lines)}) are in segments with DATA_QUALITY = "
            "DEGRADED (data with quality problems); they are used: look at their residuals")


class TdmReader(DegreesCheckedReader):
    """CCSDS TDM (KVN) angle data: ANGLE_1/ANGLE_2 in AZEL or RADEC, several stations.

    Parameters
    ----------
    sigma_arcsec : float
        Angle sigma (arcsec) for segments without a cistrack sigma comment; for RADEC on the
        sky (on RA x cos(Dec) and on Dec).
    sites : dict or None
        Explicit sites by PARTICIPANT_1 name: NAME -> {latitude_deg, longitude_deg, height_m}
        or {longitude_deg, rho_cos_phi, rho_sin_phi}.
    designation : str or None
        Read only the observations of this object (PARTICIPANT_2); None: all, refused when the
        file names several objects.
    check_degrees : bool
        Refuse a file of two or more observations whose every ANGLE_1 lies in [0, 6.2832] and
        every ANGLE_2 in [-1.5708, 1.5708], or whose one site's two or more rows all do while the
        object's other rows do not (angles written in radians, where TDM has degrees); false
        reads such a file as degrees (an object within 6.3 deg of RA or azimuth 0 and 1.6 deg of
        the equator or horizon).
    """

    suffixes = (".tdm", ".kvn")
    measurement_kinds = ("azel", "radec")

    # -- reading ---------------------------------------------------------------------------------
    def read(self, path, epoch) -> MeasurementSet:
        ep = parse_epoch(path, epoch)
        parse = _TdmParse(path, self._sites)
        parse.run(read_text_lines(path))
        _say_degraded(path, parse.degraded)
        _say_frames_ignored(path, parse.frames_ignored)
        _say_tiny_sigmas(path, parse.tiny_sigmas)
        self.checked_angles(path, parse.rows, ("ANGLE_1", "ANGLE_2"), "TDM", "tdm")
        return build_set(path, parse.rows, ep, parse.table, self.sigma_arcsec, {"format": "tdm"}, self.designation)

    # -- writing ---------------------------------------------------------------------------------
    def write(self, path, measurements, epoch) -> None:
        ms = measurements
        who = f"reader 'tdm' writing {path}"
        ep = parse_epoch(path, epoch)
        if ms.sites is None:
            raise MeasurementError(f"{who}: TDM needs the observing station (PARTICIPANT_1); the set has no sites")
        if len(ms) == 0:
            raise MeasurementError(f"{who}: no measurements to write")
        kinds = [ms.kind_at(k) for k in range(len(ms))]
        if any(k not in ("azel", "radec") for k in kinds):
            raise MeasurementError(f"{who}: TDM angles are AZEL or RADEC; this set has names {ms.names}")
        bad = sorted({s for s in ms.sites.tolist() if not s or any(c.isspace() for c in s) or "=" in s})
        if bad:
            raise MeasurementError(f"{who}: station names {bad} cannot be TDM participants (no spaces or '=')")
        out = ["CCSDS_TDM_VERS = 2.0", f"CREATION_DATE = {format_utc(ep)[:-1]}", "ORIGINATOR = cistrack"]
        k = 0
        while k < len(ms):
            j = k
            key, texts = (str(ms.sites[k]), kinds[k]), _sigma_texts(ms, k, kinds[k])
            while j + 1 < len(ms) and (str(ms.sites[j + 1]), kinds[j + 1]) == key \
                    and _reads_back(texts, ms, j + 1, kinds[k]):
                j += 1
            out += self._segment(ms, k, j, kinds[k], ep, texts)
            k = j + 1
        Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")

    def _segment(self, ms, k, j, kind, ep, sigma_texts: tuple[str, str]) -> list[str]:
        name = str(ms.sites[k])
        site = ms.site_table[name]
        out = ["", "META_START"]
        try:
            is_code = observatory(name) == site
        except MeasurementError:
            is_code = False
        if not is_code:
            out.append(f"COMMENT cistrack site {name} latitude_deg={site.latitude_deg!r} "
                       f"longitude_deg={site.longitude_deg!r} height_m={site.height_m!r}")
        out.append(f"COMMENT cistrack sigma_arcsec ANGLE_1={sigma_texts[0]} ANGLE_2={sigma_texts[1]}")
        out += ["TIME_SYSTEM = UTC", f"PARTICIPANT_1 = {name}", f"PARTICIPANT_2 = {ms.meta.get('object', 'cis0001')}",
                "MODE = SEQUENTIAL", "PATH = 2,1", f"ANGLE_TYPE = {kind.upper()}"]
        if kind == "radec":
            out.append("REFERENCE_FRAME = ICRF")
        out += ["META_STOP", "", "DATA_START"]
        for i in range(k, j + 1):
            t = format_utc(tu_to_utc(ep, ms.times[i]))[:-1]
            a = float(ms.values[i, 0]) % (2.0 * math.pi)
            out.append(f"ANGLE_1 = {t} {from_rad(a, 'deg')}")
            out.append(f"ANGLE_2 = {t} {from_rad(float(ms.values[i, 1]), 'deg')}")
        out.append("DATA_STOP")
        return out


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "tdm", TdmReader)
