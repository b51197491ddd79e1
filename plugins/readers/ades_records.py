"""IAU ADES optical observations, shared by the PSV and XML readers and writers.

A record is a mapping field name -> (text, line). The fields cistrack reads:

==========  ===================================================================================
obsTime     UTC, ISO-8601 ending in Z (required; a time without the Z, or with another zone,
            is refused, and so is a leap second, 23:59:60)
ra, dec     topocentric astrometric RA and Dec, decimal degrees (required)
rmsRA       RA uncertainty x cos(dec), arcsec (optional; else the reader's ``sigma_arcsec``)
rmsDec      Dec uncertainty, arcsec (optional). Values below 1 milliarcsecond are used with a
            warning asking whether they are degrees (:func:`say_tiny_sigmas`)
stn         MPC observatory code (required); sites outside the bundled table come from the
            reader's ``sites`` parameter or from sys = WGS84 (ctr = 399, the Earth, or absent)
            with pos1 (East longitude, deg), pos2 (latitude, deg), pos3 (height, m). A position
            is that record's own: given under a code with a place of its own (bundled or in
            ``sites``) and away from it, the record's site key is ``CODE@lat,lon,height`` and the
            code's other records keep its place; more than 1 km away, with a warning naming both
            places (once per position and file). A code with no place of its own (not bundled,
            not in ``sites``) takes one position per file; a roving observer (247, 270) any number
mode        optional, written "CCD"; radar records (RAD) are left out with a warning, as the
            XML reader leaves out ``<radar>`` elements (a file of nothing else is refused); a
            mode not among those of optical astrometry (:data:`OPTICAL_MODES`) is read with a warning
rmsCorr     optional correlation of the RA and Dec errors: refused outside [-1, 1], else not used
permID / provID / artSat / trkSub   the object (one of them required; artSat: an artificial satellite)
==========  ===================================================================================

Other ADES fields (astCat, mag, band, notes, ...) are accepted and ignored; the writer writes
astCat (required by ADES) from ``meta["astCat"]`` or "Gaia3".
"""
from __future__ import annotations

import dataclasses
import logging
import math
from datetime import datetime

from cistrack.errors import MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.component import sigma_arcsec_problem
from cistrack.interfaces.reader import FieldError, show_field
from cistrack.astro.sites import Site, observatory
from cistrack.units import ARCSEC_RAD, format_utc, tu_to_utc

from .decimal_units import from_rad, plain_float, to_rad
from .obs_rows import ObsRow, parse_iso_utc
from .site_params import DegreesCheckedReader, place_text, replaced_code, resolve_site

__all__ = ["AdesReader", "record_to_row", "rows_for_writing", "WRITE_FIELDS", "POS_FIELDS", "OPTICAL_MODES", "is_radar",
           "say_skipped", "say_tiny_sigmas", "SMALLEST_PLAUSIBLE_ARCSEC"]

WRITE_FIELDS = ("trkSub", "mode", "stn", "obsTime", "ra", "dec", "rmsRA", "rmsDec", "astCat")
POS_FIELDS = ("sys", "ctr", "pos1", "pos2", "pos3")
_ID_FIELDS = ("permID", "provID", "artSat", "trkSub")
"""The fields naming the object, in the order one is taken when several are given (ADES 2022:
permID with or without provID, provID, or artSat; trkSub beside any of them or alone)."""
ROVING_CODES = ("247", "270")
"""MPC codes of roving observers: each position given under them is a site of its own."""


def _get(rec, name, path, line, required=True):
    if name in rec and rec[name][0].strip():
        return rec[name][0].strip(), rec[name][1]
    if required:
        raise FieldError(path, line, name, "required field is missing or empty")
    return None, line


def _angle(rec, name, path, line, bounds: tuple[float, float, str], scale=1.0, unit="deg"):
    """The angle ``name`` (rad) inside ``bounds`` (lo, hi, "]" or ")": degrees, hi included or not:
    RA's 360 is 0); the refusal quotes the interval checked (RA's had said [0.0, 360.0] while 360
    was refused apart: probe I8)."""
    lo, hi, end = bounds
    text, ln = _get(rec, name, path, line)
    try:
        v = to_rad(text, unit, scale)
    except ValueError as exc:
        raise FieldError(path, ln, name, f"{show_field(text)} is {exc}") from None
    lo_r, hi_r = math.radians(lo), math.radians(hi)
    if unit == "deg" and not (lo_r <= v < hi_r if end == ")" else lo_r <= v <= hi_r):
        raise FieldError(path, ln, name, f"{show_field(text)} is outside [{lo:g}, {hi:g}{end} degrees")
    return v


def _sigma(rec, name, path, line, scale=1.0):
    text, ln = _get(rec, name, path, line, required=False)
    if text is None:
        return None
    try:
        v = to_rad(text, "arcsec", scale)
    except ValueError as exc:
        raise FieldError(path, ln, name, f"{show_field(text)} is {exc}") from None
    problem = sigma_arcsec_problem(float(text)) if v > 0 else "must be > 0 arcsec"
    if problem:
        raise FieldError(path, ln, name, f"{show_field(text)} {problem}")
    return v


def _position_value(rec, name: str, path, line: int) -> tuple[float, int]:
    """The number in position field ``name`` and its line; FieldError when it is none or not finite."""
    text, pln = _get(rec, name, path, line)
    try:
        v = plain_float(text)
    except ValueError:
        raise FieldError(path, pln, name, f"{show_field(text)} is not a number") from None
    if not math.isfinite(v):
        raise FieldError(path, pln, name, f"{show_field(text)} is not finite")
    return v, pln


def _file_position(rec, path, line: int, stn: str) -> Site:
    """The site a record gives itself (sys = WGS84, ctr = 399 or absent, pos1 East longitude,
    pos2 latitude, pos3 height m); FieldError naming the field otherwise."""
    sys_text, sln = _get(rec, "sys", path, line)
    if sys_text != "WGS84":
        raise FieldError(path, sln, "sys", f"{show_field(sys_text)}: only WGS84 (geodetic) positions are read")
    ctr, cln = _get(rec, "ctr", path, line, required=False)
    if ctr is not None and ctr != "399":
        raise FieldError(path, cln, "ctr", f"{show_field(ctr)}: a WGS84 position is on the Earth: ctr = 399 (or "
                                           "no ctr); positions about other centres are not read")
    lon, lon_line = _position_value(rec, "pos1", path, line)
    lat, lat_line = _position_value(rec, "pos2", path, line)
    height, _ = _position_value(rec, "pos3", path, line)
    if not -180.0 <= lon <= 360.0:  # ADES pos1: East longitude, degrees
        raise FieldError(path, lon_line, "pos1", f"{show_field(rec['pos1'][0])} is outside [-180, 360] degrees "
                                                 "(East longitude)")
    try:
        return Site(lat, lon if lon <= 180 else lon - 360.0, height, name=stn)
    except MeasurementError as exc:
        raise FieldError(path, lat_line, "pos1/pos2/pos3", str(exc).split(": ", 1)[-1]) from None


def _code_site(stn: str, explicit: dict[str, Site]) -> Site | None:
    """The site ``stn`` names without a position (the reader's ``sites``, else the bundled MPC
    list), or None when it names none (a code of no fixed place, or no code at all)."""
    try:
        return resolve_site(stn, explicit)
    except MeasurementError:
        return None


def _same_place(a: Site, b: Site) -> bool:
    return (a.latitude_deg, a.longitude_deg, a.height_m) == (b.latitude_deg, b.longitude_deg, b.height_m)


def _position_key(stn: str, site: Site, base: Site | None) -> str:
    """The table key of a record at ``site`` under code ``stn`` (``base``: the code's own place):
    the code itself at the code's own place, or for a code that has none (except a roving
    observer's); else the code with the position, ``CODE@lat,lon,height`` (that record's own site)."""
    if base is not None and _same_place(site, base):
        return stn
    if base is None and stn not in ROVING_CODES:
        return stn
    return f"{stn}@{site.latitude_deg!r},{site.longitude_deg!r},{site.height_m!r}"


def _given_site(rec, path, line: int, stn: str, explicit: dict[str, Site], table: dict[str, Site]) -> str:
    """The table key of a record that gives its own position, entered in ``table``: a position is
    the record's own, so one away from the code's place has a key of its own (rows of the code
    without a position keep the code's place); a warning (logger ``cistrack.readers``, once per
    position and file) when it lies more than 1 km from a bundled MPC observatory code's place."""
    site = _file_position(rec, path, line, stn)
    base = _code_site(stn, explicit)
    key = _position_key(stn, site, base)
    if key in table:
        if not _same_place(table[key], site):
            raise FieldError(path, rec["pos1"][1], "pos1", f"station {show_field(stn)} was given another position "
                                                           f"on an earlier line of the file; a station outside the "
                                                           f"MPC list and the reader's sites has one position")
        return key
    if base is not None and _same_place(site, base):
        table[key] = base
        return key
    known = replaced_code(stn, site)
    if known is not None:
        logging.getLogger("cistrack.readers").warning(
            f"{path}, line {line}: station {stn!r} is given at {place_text(site)} (sys, pos1, pos2, pos3), which "
            f"replaces {known} for these observations")
    table[key] = site
    return key


def _site(rec, path, line, explicit: dict[str, Site], table: dict[str, Site]) -> str:
    """The table key of a record's site: its own position (sys, pos1..3) when it gives one, else
    its code's place (the reader's ``sites``, else the bundled MPC list), whatever other records give."""
    stn, ln = _get(rec, "stn", path, line)
    if any(rec.get(f, ("", 0))[0].strip() for f in POS_FIELDS):
        return _given_site(rec, path, line, stn, explicit, table)
    try:
        site = resolve_site(stn, explicit)
    except MeasurementError as exc:
        raise FieldError(path, ln, "stn", f"{exc}, or this row's position (sys = WGS84, pos1, pos2, pos3): a "
                                          "position given on another row is that row's only") from None
    table.setdefault(stn, site)
    return stn


OPTICAL_MODES = ("CCD", "CMO", "VID", "PHO", "ENC", "PMT", "MIC", "MER", "TDI", "OCC", "UNK")
"""ADES ``mode`` values of optical astrometry (instruments that measure RA/Dec); another mode
(other than radar, RAD) is read as optical with a warning, once per file and mode."""

_WARNED_MODES: set[tuple[str, str]] = set()


def is_radar(rec: dict) -> bool:
    """Whether an ADES record is a radar observation (``mode`` RAD): skipped, as ``<radar>`` is."""
    return rec.get("mode", ("", 0))[0].strip() == "RAD"


def say_skipped(path, skipped: dict[str, int], any_optical: bool) -> None:
    """Refuse a file of other observations only (``skipped``: count by kind, e.g. "<radar>", "mode
    RAD"); warn (logger ``cistrack.readers``) of those left out beside optical ones."""
    if not skipped:
        return
    what = ", ".join(f"{n} {name}" for name, n in sorted(skipped.items()))
    if not any_optical:
        raise FieldError(path, 1, "(observations)", f"the file holds {what} records and no optical one: cistrack "
                                                    "reads optical astrometry (RA/Dec) only")
    logging.getLogger("cistrack.readers").warning(f"{path}: {what} records are not read (cistrack reads optical "
                                                  "astrometry only)")


SMALLEST_PLAUSIBLE_ARCSEC = 0.001
"""The smallest stated angle uncertainty (arcsec, 1 milliarcsecond) taken without a warning: no
astrometry, from the ground or from space, is finer; one below it is most likely in degrees."""


def _stated_arcsec(row: ObsRow) -> dict[str, float]:
    """The uncertainties a row states, by ADES field, arcsec (rmsRA on RA x cos(Dec))."""
    out = {}
    if row.sigma_a is not None:
        out["rmsRA"] = row.sigma_a * math.cos(row.b) / ARCSEC_RAD
    if row.sigma_b is not None:
        out["rmsDec"] = row.sigma_b / ARCSEC_RAD
    return out


class AdesReader(DegreesCheckedReader):
    """What the ADES readers (PSV, XML) share: :class:`SiteReader`'s parameters and ``check_degrees``.

    Parameters
    ----------
    sigma_arcsec : float
        Sigma on the sky (arcsec: on RA x cos(Dec), like rmsRA, and on Dec) for observations
        without rmsRA / rmsDec.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC list: CODE ->
        {latitude_deg, longitude_deg, height_m[, name]} or {longitude_deg, rho_cos_phi,
        rho_sin_phi[, name]}.
    designation : str or None
        Read only the observations of this object (permID / provID / artSat / trkSub); None:
        all, refused when the file names several objects.
    check_degrees : bool
        Refuse a file of two or more observations whose every ra lies in [0, 6.2832] and every
        dec in [-1.5708, 1.5708], or whose one site's two or more rows all do while the object's
        other rows do not (angles written in radians, where ADES has degrees; as the tdm reader
        does); false reads such a file as degrees (an object within 6.3 deg of RA 0 and 1.6 deg
        of the equator).
    sigma_from_file : bool
        true (default): rows that state rmsRA / rmsDec keep them; false: every row takes
        ``sigma_arcsec`` instead (a file whose stated uncertainties are wrong).
    """

    def __init__(self, sigma_arcsec: float = 1.0, sites: dict | None = None, designation: str | None = None,
                 check_degrees: bool = True, sigma_from_file: bool = True) -> None:
        super().__init__(sigma_arcsec, sites, designation, check_degrees)
        if not isinstance(sigma_from_file, bool):
            self._fail("sigma_from_file", sigma_from_file, "must be true or false")
        self.sigma_from_file = sigma_from_file

    def sigma_meta(self) -> dict:
        """What the set's meta records of ``sigma_from_file``: ``{"sigma_from_file": False}`` when it
        is off (the weights line then says the file's own were replaced), else nothing."""
        return {} if self.sigma_from_file else {"sigma_from_file": False}

    def checked_rows(self, path, rows: list[ObsRow]) -> list[ObsRow]:
        """``rows`` of ``path``, refused when their angles read as radians (``check_degrees``;
        probe L8: such a file had been fitted and its misfit blamed on a maneuver); without their
        stated uncertainties when ``sigma_from_file`` is false."""
        rows = self.checked_angles(path, rows, ("ra", "dec"), "ADES", self.registry_name or "ades")
        return rows if self.sigma_from_file else [dataclasses.replace(r, sigma_a=None, sigma_b=None) for r in rows]


def say_tiny_sigmas(path, rows: list[ObsRow]) -> None:
    """Warn (logger ``cistrack.readers``, once per field and file) of rmsRA or rmsDec values below
    :data:`SMALLEST_PLAUSIBLE_ARCSEC`: arcseconds by the standard, but likely degrees by mistake
    (weights some 3600 times too tight make a fit fail far from the data). They are used as given."""
    for name in ("rmsRA", "rmsDec"):
        tiny = [(r.line, v) for r in rows for f, v in _stated_arcsec(r).items() if f == name
                and v < SMALLEST_PLAUSIBLE_ARCSEC]
        if tiny:
            logging.getLogger("cistrack.readers").warning(
                f"{path}, line {tiny[0][0]}: field {name}: {len(tiny)} observations state an uncertainty below 1 "
                f"milliarcsecond (this one {tiny[0][1]:.3g} arcsec); ADES {name} is in arcseconds: are these "
                "degrees? They are used as given")


def _check_optical(rec, path, line: int) -> None:
    """Refuse a radar record (``mode`` RAD) or one whose ``rmsCorr`` (the correlation of the RA and
    Dec errors) is not a number in [-1, 1]; warn of a mode that is not a known optical one."""
    mode, mln = _get(rec, "mode", path, line, required=False)
    if mode == "RAD":
        raise FieldError(path, mln, "mode", f"{show_field(mode)}: radar observations are not read; cistrack "
                                            f"reads optical RA/Dec (mode {', '.join(OPTICAL_MODES)})")
    if mode is not None and mode not in OPTICAL_MODES and (str(path), mode) not in _WARNED_MODES:
        _WARNED_MODES.add((str(path), mode))
        logging.getLogger("cistrack.readers").warning(
            f"warning: {path}: line {mln}: mode {show_field(mode)} is not an optical mode cistrack knows "
            f"({', '.join(OPTICAL_MODES)}); its rows are read as optical RA/Dec")
    corr, cln = _get(rec, "rmsCorr", path, line, required=False)
    if corr is not None:
        try:
            value = plain_float(corr)
        except ValueError:
            value = math.nan
        if not -1.0 <= value <= 1.0:
            raise FieldError(path, cln, "rmsCorr", f"{show_field(corr)}: a correlation must be a number in [-1, 1]")


def record_to_row(rec: dict, path, line: int, explicit: dict[str, Site], table: dict[str, Site]) -> ObsRow:
    """One ADES optical record -> ObsRow (RA/Dec in rad); FieldError naming line and field."""
    if not any(rec.get(f, ("", 0))[0].strip() for f in _ID_FIELDS):
        raise FieldError(path, line, "permID/provID/artSat/trkSub", "the observation names no object")
    _check_optical(rec, path, line)
    text, tln = _get(rec, "obsTime", path, line)
    try:
        t = parse_iso_utc(text)
    except ValueError as exc:
        raise FieldError(path, tln, "obsTime", f"{show_field(text)}: {exc}") from None
    ra = _angle(rec, "ra", path, line, (0.0, 360.0, ")"))
    dec = _angle(rec, "dec", path, line, (-90.0, 90.0, "]"))
    s_ra = _sigma(rec, "rmsRA", path, line, scale=math.cos(dec))
    s_dec = _sigma(rec, "rmsDec", path, line)
    site = _site(rec, path, line, explicit, table)
    obj = next(rec[f][0].strip() for f in _ID_FIELDS if rec.get(f, ("", 0))[0].strip())
    prov = rec.get("provID", ("", 0))[0].strip()
    alias = prov if prov and prov != obj else ""  # a permID's provID: rows named by it are this object's
    return ObsRow(t, ra, dec, s_ra, s_dec, site, "radec", line, "obsTime", obj, alias)


def rows_for_writing(ms: MeasurementSet, epoch: datetime, who: str) -> tuple[list[dict[str, str]], bool]:
    """ADES field texts of each measurement, and whether position fields are needed."""
    kinds = set(ms.kinds.tolist()) if ms.kinds is not None else {"radec" if ms.names[:2] == ("right_ascension", "declination") else "?"}
    if kinds != {"radec"}:
        raise MeasurementError(f"{who}: ADES optical observations are RA/Dec; this set has types "
                               f"{sorted(kinds)} (write az/el as csv or tdm)")
    if ms.sites is None:
        raise MeasurementError(f"{who}: ADES needs the observing station of each measurement; the set has no sites")
    obj = str(ms.meta.get("object", "cis0001"))
    cat = str(ms.meta.get("astCat", "Gaia3"))
    out, need_pos = [], False
    for k in range(len(ms)):
        key = str(ms.sites[k])
        site = ms.site_table[key]
        try:
            is_code = observatory(key) == site
        except MeasurementError:
            is_code = False
        dec = float(ms.values[k, 1])
        rec = {"trkSub": obj, "mode": "CCD", "stn": key.split("@")[0] if not is_code else key,
               "obsTime": format_utc(tu_to_utc(epoch, ms.times[k])),
               "ra": from_rad(float(ms.values[k, 0]) % (2 * math.pi), "deg"), "dec": from_rad(dec, "deg"),
               "rmsRA": from_rad(float(ms.sigmas[k, 0]), "arcsec", scale=math.cos(dec)),
               "rmsDec": from_rad(float(ms.sigmas[k, 1]), "arcsec"), "astCat": cat}
        if not is_code:
            need_pos = True
            rec.update({"sys": "WGS84", "ctr": "399", "pos1": repr(float(site.longitude_deg)),
                        "pos2": repr(float(site.latitude_deg)), "pos3": repr(float(site.height_m))})
        out.append(rec)
    return out, need_pos
