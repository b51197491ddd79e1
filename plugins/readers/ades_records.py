"""IAU ADES optical observations, shared by the PSV and XML readers and writers.

A record is a mapping field name -> (text, line). The fields cistrack reads:

==========  ===================================================================================
obsTime     UTC, ISO-8601 ending in Z (required)
ra, dec     topocentric astrometric RA and Dec, decimal degrees (required)
rmsRA       RA uncertainty x cos(dec), arcsec (optional; else the reader's ``sigma_arcsec``)
rmsDec      Dec uncertainty, arcsec (optional)
stn         MPC observatory code (required); sites outside the bundled table come from the
            reader's ``sites`` parameter or from sys = WGS84 with pos1 (East longitude, deg),
            pos2 (latitude, deg), pos3 (height, m)
mode        optional, written "CCD"
permID / provID / trkSub   the object (one of them required)
==========  ===================================================================================

Other ADES fields (astCat, mag, band, notes, ...) are accepted and ignored; the writer writes
astCat (required by ADES) from ``meta["astCat"]`` or "Gaia3".
"""
from __future__ import annotations

import math
from datetime import datetime

from cistrack.errors import MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.component import sigma_arcsec_problem
from cistrack.interfaces.reader import FieldError, show_field
from cistrack.astro.sites import Site, observatory
from cistrack.units import format_utc, tu_to_utc

from .decimal_units import from_rad, plain_float, to_rad
from .obs_rows import ObsRow, parse_iso_utc
from .site_params import resolve_site

__all__ = ["record_to_row", "rows_for_writing", "WRITE_FIELDS", "POS_FIELDS"]

WRITE_FIELDS = ("trkSub", "mode", "stn", "obsTime", "ra", "dec", "rmsRA", "rmsDec", "astCat")
POS_FIELDS = ("sys", "ctr", "pos1", "pos2", "pos3")
_ID_FIELDS = ("permID", "provID", "trkSub")


def _get(rec, name, path, line, required=True):
    if name in rec and rec[name][0].strip():
        return rec[name][0].strip(), rec[name][1]
    if required:
        raise FieldError(path, line, name, "required field is missing or empty")
    return None, line


def _angle(rec, name, path, line, lo, hi, scale=1.0, unit="deg"):
    text, ln = _get(rec, name, path, line)
    try:
        v = to_rad(text, unit, scale)
    except ValueError as exc:
        raise FieldError(path, ln, name, f"{show_field(text)} is {exc}") from None
    lo_r, hi_r = math.radians(lo), math.radians(hi)
    if unit == "deg" and not lo_r <= v <= hi_r:
        raise FieldError(path, ln, name, f"{show_field(text)} is outside [{lo}, {hi}] degrees")
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


def _site(rec, path, line, explicit: dict[str, Site], table: dict[str, Site]) -> str:
    stn, ln = _get(rec, "stn", path, line)
    has_pos = any(rec.get(f, ("", 0))[0].strip() for f in POS_FIELDS)
    if has_pos:
        sys_text, sln = _get(rec, "sys", path, line)
        if sys_text != "WGS84":
            raise FieldError(path, sln, "sys", f"{show_field(sys_text)}: only WGS84 (geodetic) positions are read")
        vals = []
        for f in ("pos1", "pos2", "pos3"):
            text, pln = _get(rec, f, path, line)
            try:
                v = plain_float(text)
            except ValueError:
                raise FieldError(path, pln, f, f"{show_field(text)} is not a number") from None
            if not math.isfinite(v):
                raise FieldError(path, pln, f, f"{show_field(text)} is not finite")
            vals.append((v, pln, f))
        if not -180.0 <= vals[0][0] <= 360.0:  # ADES pos1: East longitude, degrees
            raise FieldError(path, vals[0][1], "pos1", f"{show_field(rec['pos1'][0])} is outside [-180, 360] degrees "
                                                       "(East longitude)")
        try:
            site = Site(vals[1][0], vals[0][0] if vals[0][0] <= 180 else vals[0][0] - 360.0, vals[2][0], name=stn)
        except MeasurementError as exc:
            raise FieldError(path, vals[1][1], "pos1/pos2/pos3", str(exc).split(": ", 1)[-1]) from None
        key = stn if stn != "247" else f"247@{vals[1][0]!r},{vals[0][0]!r},{vals[2][0]!r}"
        if key in table and table[key] != site:
            raise FieldError(path, vals[0][1], "pos1", f"station {show_field(stn)} was given another position "
                                                       f"earlier in the file")
        table[key] = site
        return key
    if stn not in table:
        try:
            table[stn] = resolve_site(stn, explicit)
        except MeasurementError as exc:
            raise FieldError(path, ln, "stn", str(exc)) from None
    return stn


def record_to_row(rec: dict, path, line: int, explicit: dict[str, Site], table: dict[str, Site]) -> ObsRow:
    """One ADES optical record -> ObsRow (RA/Dec in rad); FieldError naming line and field."""
    if not any(rec.get(f, ("", 0))[0].strip() for f in _ID_FIELDS):
        raise FieldError(path, line, "permID/provID/trkSub", "the observation names no object")
    text, tln = _get(rec, "obsTime", path, line)
    try:
        t = parse_iso_utc(text)
    except ValueError as exc:
        raise FieldError(path, tln, "obsTime", f"{show_field(text)}: {exc}") from None
    ra = _angle(rec, "ra", path, line, 0.0, 360.0)
    if ra >= 2.0 * math.pi:
        raise FieldError(path, rec["ra"][1], "ra", f"{show_field(rec['ra'][0])} must be below 360 degrees")
    dec = _angle(rec, "dec", path, line, -90.0, 90.0)
    s_ra = _sigma(rec, "rmsRA", path, line, scale=math.cos(dec))
    s_dec = _sigma(rec, "rmsDec", path, line)
    site = _site(rec, path, line, explicit, table)
    obj = next(rec[f][0].strip() for f in _ID_FIELDS if rec.get(f, ("", 0))[0].strip())
    return ObsRow(t, ra, dec, s_ra, s_dec, site, "radec", line, "obsTime", obj)


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
