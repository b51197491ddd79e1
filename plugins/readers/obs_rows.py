"""Building a MeasurementSet from parsed observation rows, shared by the readers.

Each reader parses its syntax into :class:`ObsRow` (time, two angles in rad, optional sigmas,
site key, type, and the line each came from) and hands them to :func:`build_set`, which sorts
by time, refuses two observations of one site at the same time with both lines named (several
sites may share a time), and fills the per-measurement sites and types. Times are given as UTC datetimes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from datetime import datetime, timezone

import numpy as np

from cistrack.model.measurement import KIND_NAMES, MeasurementSet
from cistrack.interfaces.reader import FieldError, SeveralObjectsError, show_field
from cistrack.astro.sites import Site
from cistrack.units import ARCSEC_RAD, LEAP_SECOND_PROBLEM, date_problem, format_utc, is_leap_second, parse_utc, utc_to_tu

from .decimal_units import to_rad

__all__ = ["check_degrees", "ObsRow", "build_set", "one_object", "parse_epoch", "parse_iso_utc", "year_problem", "TIME_FIELD_HELP",
           "FIRST_YEAR", "LAST_YEAR", "is_leap_second", "LEAP_SECOND_PROBLEM"]

TIME_FIELD_HELP = "an ISO-8601 UTC time such as 2026-03-01T03:40:00.000000Z"
FIRST_YEAR, LAST_YEAR = 1800, 2199
"""The years an observation may lie in: those of a scenario's span (cistrack.scenario.work_limits),
whose time scales cistrack supports and whose dates never overflow."""


def year_problem(t: datetime) -> str | None:
    """Why the observation time ``t`` cannot be used (outside FIRST_YEAR..LAST_YEAR), or None."""
    if FIRST_YEAR <= t.year <= LAST_YEAR:
        return None
    return (f"time {t.year:04d}-{t.month:02d}-{t.day:02d} is outside the years cistrack supports "
            f"({FIRST_YEAR} to {LAST_YEAR})")


@dataclass
class ObsRow:
    """One parsed observation: ``t`` UTC, angles (rad), sigmas (rad, on the angles themselves:
    the RA sigma is the RA x cos(Dec) sigma / cos(Dec); or None: the reader's default)."""

    t: datetime
    a: float
    b: float
    sigma_a: float | None
    sigma_b: float | None
    site: str
    kind: str
    line: int
    time_field: str
    obj: str = ""
    """The object's designation in the file ("": the format names none)."""
    alias: str = ""
    """Another designation the row gives the same object (ADES: the provID of a row named by its
    permID), linking rows that name it only that way."""


def _radians_box(r: ObsRow) -> bool:
    """Whether ``r``'s angles, read as degrees, lie within [0, 2 pi] x [-pi/2, pi/2]: as radians would."""
    deg = math.pi / 180.0
    return r.a <= 2.0 * math.pi * deg and abs(r.b) <= 0.5 * math.pi * deg


def _sites_in_radians(rows: list[ObsRow]) -> dict[str, list[ObsRow]]:
    """The sites (key -> their rows of one object and type, in file order) whose two or more rows
    all lie in the radians box while some of that object's other rows do not, and, for RA/Dec,
    read as radians lie nearer the object's other rows than as written (:func:`_nearer_as_radians`:
    a real object near RA 3 deg and the equator seen by one site stays as written)."""
    groups: dict[tuple[str, str, str], list[ObsRow]] = {}
    for r in rows:
        groups.setdefault((r.obj, r.site, r.kind), []).append(r)
    elsewhere = {r.obj for r in rows if not _radians_box(r)}
    return {site: v for (obj, site, kind), v in groups.items()
            if obj in elsewhere and len(v) >= 2 and all(_radians_box(r) for r in v)
            and (kind != "radec" or _nearer_as_radians(v, [r for r in rows if r.obj == obj and r.site != site
                                                           and r.kind == kind]))}


def _nearer_as_radians(mine: list[ObsRow], others: list[ObsRow]) -> bool:
    """Whether the rows ``mine`` (RA/Dec), their values read as radians, lie nearer the rows of
    ``others`` closest to them in time than as written (medians of the angles on the sky): the
    object's other sites see it where a site's radians put it."""
    if not others:
        return True
    t_other = np.array([o.t.timestamp() for o in others])
    near = [others[int(np.argmin(np.abs(t_other - r.t.timestamp())))] for r in mine]
    scale = 180.0 / math.pi  # a value written in radians and read as degrees is this much too small
    as_read = np.median([_separation(r.a, r.b, o.a, o.b) for r, o in zip(mine, near)])
    as_rad = np.median([_separation(r.a * scale, r.b * scale, o.a, o.b) for r, o in zip(mine, near)])
    return bool(as_rad < as_read)


def _separation(a1: float, b1: float, a2: float, b2: float) -> float:
    """Angle (rad) between two directions given by longitude and latitude (rad)."""
    c = math.sin(b1) * math.sin(b2) + math.cos(b1) * math.cos(b2) * math.cos(a1 - a2)
    return math.acos(max(-1.0, min(1.0, c)))


def check_degrees(path, rows: list[ObsRow], fields: tuple[str, str], standard: str, reader: str) -> None:
    """Refuse angles that read as radians (FieldError naming ``path``, the first such row's line and
    the ``fields``): two or more observations, every first angle within [0, 2 pi] and every second
    within [-pi/2, pi/2] (values as written, degrees by the ``standard``: "TDM", "ADES"), in the
    whole file or in all of one site's rows (two or more) while other sites' rows lie elsewhere;
    the message names the site and the ``reader``'s parameter ``check_degrees`` that reads such a
    file as degrees."""
    if len(rows) < 2:
        return
    if all(_radians_box(r) for r in rows):
        site, site_rows, which = None, rows, f"all {len(rows)} observations have"
    else:
        suspect = _sites_in_radians(rows)
        if not suspect:
            return
        site, site_rows = next(iter(suspect.items()))
        which = f"all {len(site_rows)} observations of site {site} have"
    one, two = fields
    but = "" if site is None else " while the other sites' do not"
    raise FieldError(path, site_rows[0].line, f"{one}/{two} values",
                     f"{which} {one} within [0, 6.2832] and {two} within [-1.5708, 1.5708]{but}: these look "
                     f"like radians, but {standard} angles are degrees; write the angles in degrees (radians x "
                     f"57.29578), or set the {reader} reader's check_degrees = false "
                     "(--set measurements.reader.check_degrees=false) if they are degrees")


def parse_epoch(path, epoch) -> datetime:
    try:
        return parse_utc(epoch)
    except (ValueError, TypeError):
        from cistrack.errors import MeasurementError
        raise MeasurementError(f"{path}: epoch {epoch!r} is not an ISO-8601 UTC time") from None


def parse_iso_utc(text: str) -> datetime:
    """An ISO-8601 UTC time ending in Z, as ADES writes it ('2026-03-01T03:40:00.5Z'); ValueError
    otherwise (a time with another zone, +00:00 or none, a leap second)."""
    s = text.strip()
    if not s or "T" not in s:
        raise ValueError("not " + TIME_FIELD_HELP)
    if is_leap_second(s):
        raise ValueError(LEAP_SECOND_PROBLEM)
    try:
        dt = parse_utc(s)
    except ValueError:  # the caller quotes the text: say why once, not the text again
        raise ValueError(date_problem(s) or "not " + TIME_FIELD_HELP) from None
    if not s.endswith("Z"):
        raise ValueError("must be UTC (end in Z)")
    return dt.astimezone(timezone.utc)


def _default_first(row: ObsRow, sigma_arcsec: float, default_rad: float) -> float:
    """The reader's default sigma of a row's first angle, rad: on the sky for RA/Dec (sigma_arcsec
    on RA x cos(Dec), so sigma_arcsec / cos(Dec) on RA, correctly rounded), as is for az/el."""
    if row.kind != "radec":
        return default_rad
    return to_rad(repr(float(sigma_arcsec)), "arcsec", scale=math.cos(row.b))


def _linked(rows: list[ObsRow]) -> list[ObsRow]:
    """``rows`` with each row named by a designation another row gives as its alias (an ADES
    provID beside a permID) named as that row is: one object, not two."""
    names = {r.alias: r.obj for r in rows if r.alias and r.obj}
    if not names:
        return rows
    return [replace(r, obj=names[r.obj]) if r.obj in names else r for r in rows]


def _refuse_unnamed(path, rows: list[ObsRow], objects: list[str]) -> None:
    """FieldError when some rows name no object (a TDM segment without PARTICIPANT_2) beside rows
    naming several objects: whose observations they are is unknown (beside one object they are
    that object's)."""
    unnamed = [r for r in rows if not r.obj]
    if unnamed and len(objects) > 1:
        shown = ", ".join(show_field(o) for o in objects[:5]) + (", ..." if len(objects) > 5 else "")
        raise FieldError(path, min(r.line for r in unnamed), "(object)",
                         f"{len(unnamed)} of the file's {len(rows)} observations (the first on this line) name no "
                         f"object, beside observations of {len(objects)} objects ({shown}): which object they are "
                         "of is unknown; name the object of each (TDM PARTICIPANT_2 in every segment) or give "
                         "them a file of their own")


def one_object(path, rows: list[ObsRow], designation: str | None) -> tuple[list[ObsRow], str | None]:
    """The rows of one object and its designation: those of ``designation`` when given (a
    FieldError when the file has none), else all rows, refused with :class:`SeveralObjectsError`
    when they name several objects. Rows naming no object are those of the one object the file
    names; beside several they are refused (:func:`_refuse_unnamed`), never left out."""
    rows = _linked(rows)
    bad = next((r for r in rows if not (r.obj.isprintable() and r.alias.isprintable())), None)
    if bad is not None:  # a designation is printed: a control character in it would act on the terminal
        name = bad.obj if not bad.obj.isprintable() else bad.alias
        raise FieldError(path, bad.line, "(object)", f"{show_field(name)}: a designation must be printable "
                                                     "characters (no control characters)")
    objects = list(dict.fromkeys(r.obj for r in rows if r.obj))
    _refuse_unnamed(path, rows, objects)
    if designation is not None:
        designation = {r.alias: r.obj for r in rows if r.alias}.get(designation, designation)
        if designation not in objects:
            raise FieldError(path, 1, "(designation)", f"no observation of object {show_field(designation)}; the "
                                                       f"file names {', '.join(objects) or 'no object'}")
        return [r for r in rows if r.obj in (designation, "")], designation
    if len(objects) > 1:
        raise SeveralObjectsError(path, objects)
    return rows, (objects[0] if objects else None)


def _refuse_repeats(path, rows: list[ObsRow]) -> None:
    """FieldError for a row at the time and site of an earlier one (the same observation twice,
    naming both lines); rows of different sites at one time are several observatories observing
    at once, and are kept."""
    seen: dict[tuple[datetime, str], ObsRow] = {}
    for row in rows:
        first = seen.setdefault((row.t, row.site), row)
        if first is not row:
            raise FieldError(path, row.line, row.time_field,
                             f"time {format_utc(row.t)} at site {show_field(row.site)} repeats the observation of "
                             f"line {first.line}; one site observes once at a time (other sites may share the time)")


LOWEST_SEEN_ELEVATION_DEG = -5.0
"""Elevations below this (degrees) are warned of: a ground telescope sees nothing that far under
its horizon (refraction lifts a star by about 0.6 degrees there, a mountain site's horizon dips by
about 2); such angles are most likely another quantity, or another sign, by mistake."""


def say_below_horizon(path, elevations_rad, lines) -> None:
    """Warn (logger ``cistrack.readers``, once per file) of az/el observations whose elevation lies
    below :data:`LOWEST_SEEN_ELEVATION_DEG`, naming the first one's line; they are used as given."""
    el = np.degrees(np.asarray(elevations_rad, dtype=float))
    below = np.nonzero(el < LOWEST_SEEN_ELEVATION_DEG)[0]
    if below.size:
        import logging

        k = int(below[0])
        logging.getLogger("cistrack.readers").warning(
            f"{path}, line {lines[k]}: {below.size} of {el.size} elevations lie more than "
            f"{-LOWEST_SEEN_ELEVATION_DEG:g} degrees below the horizon (this one {el[k]:.4g} deg), where a ground "
            "telescope sees nothing: are the angles another quantity, or of another sign? They are used as given")


def build_set(path, rows: list[ObsRow], epoch: datetime, site_table: dict[str, Site],
              sigma_arcsec: float, meta: dict | None = None, designation: str | None = None) -> MeasurementSet:
    """The MeasurementSet of ``rows`` in time order (TU elapsed since ``epoch``, leap seconds counted).

    Rows without sigmas get the reader's default ``sigma_arcsec`` on the sky: on Dec, and on
    RA x cos(Dec) (so sigma_arcsec / cos(Dec) on RA itself; az/el: on each angle). The set's meta
    records ``default_sigma_arcsec``, ``default_sigma_count`` (observations that took it on
    either angle) and ``default_sigma_partial`` (those that stated one angle's sigma only)."""
    if not rows:
        raise FieldError(path, 1, "(observations)", "the file has no observations")
    rows, obj = one_object(path, rows, designation)
    meta = {**(meta or {}), **({"object": obj} if obj else {})}
    rows = sorted(rows, key=lambda r: (r.t, r.line))
    for row in (rows[0], rows[-1]):
        if year_problem(row.t):
            raise FieldError(path, row.line, row.time_field, year_problem(row.t))
    _refuse_repeats(path, rows)
    kinds = {r.kind for r in rows}
    names = KIND_NAMES[rows[0].kind] if len(kinds) == 1 else ("angle_1", "angle_2")
    default = sigma_arcsec * ARCSEC_RAD
    times = np.array([utc_to_tu(epoch, r.t) for r in rows])  # elapsed: leap seconds counted
    values = np.array([[r.a, r.b] for r in rows])
    sigmas = np.array([[r.sigma_a if r.sigma_a is not None else _default_first(r, sigma_arcsec, default),
                        r.sigma_b if r.sigma_b is not None else default] for r in rows])
    azel = [r for r in rows if r.kind == "azel"]
    say_below_horizon(path, [r.b for r in azel], [r.line for r in azel])
    defaulted = sum(r.sigma_a is None or r.sigma_b is None for r in rows)
    partial = sum((r.sigma_a is None) != (r.sigma_b is None) for r in rows)
    used = {r.site for r in rows}
    return MeasurementSet(times, values, sigmas, names,
                          {"source": str(path), "epoch": format_utc(epoch), **(meta or {}),
                           "default_sigma_arcsec": float(sigma_arcsec), "default_sigma_count": int(defaulted),
                           "default_sigma_partial": int(partial)},
                          sites=np.array([r.site for r in rows]), kinds=np.array([r.kind for r in rows]),
                          site_table={k: v for k, v in site_table.items() if k in used})
