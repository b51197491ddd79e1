"""Earth–Moon CR3BP characteristic units and conversions.

States are nondimensional and synodic (barycentric, rotating) inside cistrack; everything a
person reads or writes is in km, km/s, days and UTC. These helpers are the one place where the
two meet.

Constants (the Earth-Moon CR3BP units used throughout): LU = 384,400 km, TU = 375,149 s (4.342 d), VU = LU/TU.

Time: t is elapsed SI seconds (in TU) since a UTC epoch, as :mod:`cistrack.astro.timescales`
evaluates it, so a UTC label and t differ by the leap seconds between the epoch and the label:
:func:`utc_to_tu`, :func:`tu_to_utc`, :func:`elapsed_seconds` and :func:`utc_after` convert
between them with ERFA's TAI-UTC table (the one astropy uses). When no leap second lies between
the epoch and the time they are plain clock arithmetic, bit for bit. An instant inside a leap
second (23:59:60.x UTC) has no Python ``datetime``: it is written as 23:59:59.999999 of that day.
"""
from __future__ import annotations

import calendar
import re
from datetime import datetime, timedelta, timezone
from functools import lru_cache

import numpy as np

LU_KM: float = 384_400.0
"""Length unit: Earth–Moon distance, km."""
TU_S: float = 375_149.0
"""Time unit: 1/n of the synodic rotation, seconds (4.342 days)."""
VU_KMS: float = LU_KM / TU_S
"""Velocity unit, km/s (about 1.02466)."""
DAY_S: float = 86_400.0
TU_DAYS: float = TU_S / DAY_S
ARCSEC_RAD: float = np.pi / (180.0 * 3600.0)
KM_SCALE: np.ndarray = np.array([LU_KM, LU_KM, LU_KM, VU_KMS, VU_KMS, VU_KMS])
"""Nondimensional synodic state -> km, km/s, per component (6,): ``state_km = state * KM_SCALE``."""

__all__ = [
    "LU_KM", "TU_S", "VU_KMS", "DAY_S", "TU_DAYS", "ARCSEC_RAD", "KM_SCALE",
    "km_to_lu", "lu_to_km", "kms_to_vu", "vu_to_kms", "days_to_tu", "tu_to_days",
    "hours_to_tu", "tu_to_hours", "seconds_to_tu", "tu_to_seconds",
    "state_to_km", "state_from_km", "parse_utc", "format_utc", "tu_to_utc", "is_leap_second", "utc_problem",
    "LEAP_SECOND_PROBLEM", "utc_to_tu", "leap_seconds", "elapsed_seconds", "utc_after", "grid_leap_seconds",
    "LAST_LEAP_SECOND_END",
]


def km_to_lu(x):
    """Distance km -> LU (array-like in, ndarray or float out)."""
    return np.asarray(x, dtype=float) / LU_KM


def lu_to_km(x):
    """Distance LU -> km."""
    return np.asarray(x, dtype=float) * LU_KM


def kms_to_vu(v):
    """Speed km/s -> VU."""
    return np.asarray(v, dtype=float) / VU_KMS


def vu_to_kms(v):
    """Speed VU -> km/s."""
    return np.asarray(v, dtype=float) * VU_KMS


def days_to_tu(d):
    """Duration days -> TU."""
    return np.asarray(d, dtype=float) * DAY_S / TU_S


def tu_to_days(t):
    """Duration TU -> days."""
    return np.asarray(t, dtype=float) * TU_S / DAY_S


def hours_to_tu(h):
    """Duration hours -> TU."""
    return np.asarray(h, dtype=float) * 3600.0 / TU_S


def tu_to_hours(t):
    """Duration TU -> hours."""
    return np.asarray(t, dtype=float) * TU_S / 3600.0


def seconds_to_tu(s):
    """Duration seconds -> TU."""
    return np.asarray(s, dtype=float) / TU_S


def tu_to_seconds(t):
    """Duration TU -> seconds."""
    return np.asarray(t, dtype=float) * TU_S


def state_to_km(states):
    """Nondimensional states (..., 6) -> km and km/s (..., 6)."""
    s = np.array(states, dtype=float, copy=True)
    s[..., :3] *= LU_KM
    s[..., 3:] *= VU_KMS
    return s


def state_from_km(states_km):
    """States in km and km/s (..., 6) -> nondimensional (..., 6)."""
    s = np.array(states_km, dtype=float, copy=True)
    s[..., :3] /= LU_KM
    s[..., 3:] /= VU_KMS
    return s


_LEAP_SECOND = re.compile(r"T\d{2}:\d{2}:60(?:[.,]\d*)?(?:Z|[+-]\d{2}:?\d{2})?$")
LEAP_SECOND_PROBLEM = "is a leap second (second 60): leap-second time tags are not supported"
"""How the observation readers and the scenario word a time with second 60 (datetime holds none)."""


def is_leap_second(text: str) -> bool:
    """Whether the ISO-8601 time ``text`` has second 60 (a leap second, which datetime cannot hold)."""
    return bool(_LEAP_SECOND.search(str(text).strip()))


def utc_problem(text: str, example: str = "2026-01-01T00:00:00Z") -> str:
    """Why :func:`parse_utc` refused ``text``, for a message after it: a leap second
    (:data:`LEAP_SECOND_PROBLEM`), else not an ISO-8601 UTC time, with ``example``."""
    return LEAP_SECOND_PROBLEM if is_leap_second(text) else f"is not an ISO-8601 UTC time (e.g. '{example}')"


_DATE = re.compile(r"\s*([+-]?\d{4})-(\d{2})-(\d{2})(?:[T ]|$)")


def date_problem(text: str) -> str:
    """Why ``text``, an ISO-8601 time whose date is well formed (YYYY-MM-DD), names no date, in
    words ("2026-02-30 is not a date: February has 28 days in 2026"); "" when the date exists or
    is not so written (then the text is no ISO-8601 time at all)."""
    found = _DATE.match(str(text))
    if not found:
        return ""
    year, month, day = (int(g) for g in found.groups())
    shown = "-".join(found.groups())
    if not 1 <= year <= 9999:
        return f"{shown} is not a date: years run from 0001 to 9999"
    if not 1 <= month <= 12:
        return f"{shown} is not a date: there is no month {found[2]} (01 to 12)"
    days = calendar.monthrange(year, month)[1]
    if not 1 <= day <= days:
        return f"{shown} is not a date: {calendar.month_name[month]} has {days} days in {year}"
    return ""


def parse_utc(text: str | datetime) -> datetime:
    """Parse an ISO-8601 UTC timestamp ('2026-01-01T00:00:00Z'); naive times are taken as UTC.

    Raises ValueError with the offending text when it is not a timestamp, saying so when its
    well-formed date does not exist (:func:`date_problem`).
    """
    if isinstance(text, datetime):
        dt = text
    else:
        s = str(text).strip()
        if s.endswith("Z"):
            s = s[:-1] + "+00:00"
        try:
            dt = datetime.fromisoformat(s)
        except ValueError as exc:
            why = date_problem(s)
            raise ValueError(f"{text!r}: {why}" if why else f"not an ISO-8601 UTC time: {text!r}") from exc
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=timezone.utc)
    return dt.astimezone(timezone.utc)


def format_utc(dt: datetime) -> str:
    """Format a datetime as 'YYYY-MM-DDTHH:MM:SS.ffffffZ'."""
    return dt.astimezone(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def leap_seconds(epoch: datetime, when: datetime) -> float:
    """Leap seconds from the UTC instant ``epoch`` to ``when`` (TAI-UTC at ``when`` minus at
    ``epoch``, s; negative when ``when`` is earlier): 0.0 when no leap second lies between them.

    From ERFA's table (``erfa.dat``); none before 1960 or after the table's last leap second, as
    :mod:`cistrack.astro.timescales` assumes. Before 1972 UTC drifted against TAI, so the value
    then has a fractional part.
    """
    if _after_the_last_leap_second(epoch) and _after_the_last_leap_second(when):
        return 0.0      # no lookup: a simulated run of today's epochs does not load ERFA
    return _tai_minus_utc(when) - _tai_minus_utc(epoch)


LAST_LEAP_SECOND_END = datetime(2017, 1, 1, tzinfo=timezone.utc)
"""The UTC midnight that ends the last leap second in ERFA's table (2016-12-31T23:59:60; TAI-UTC =
37 s since). Two times at or after it have none between them and need no lookup; tests check it
against the installed ERFA (``erfa.leap_seconds``), so a newer table with another leap second
fails them until this is moved."""


def _after_the_last_leap_second(when: datetime) -> bool:
    return (when if when.tzinfo is not None else when.replace(tzinfo=timezone.utc)) >= LAST_LEAP_SECOND_END


def _tai_minus_utc(when: datetime) -> float:
    if when.tzinfo is not None:
        when = when.astimezone(timezone.utc)
    if when.year >= 1972:  # whole leap seconds since 1972, taken at a day's end: one value per UTC day
        return _tai_minus_utc_on(when.year, when.month, when.day)
    day_s = when.hour * 3600.0 + when.minute * 60.0 + when.second + when.microsecond * 1e-6
    return _erfa_dat(when.year, when.month, when.day, day_s / DAY_S)


@lru_cache(maxsize=4096)
def _tai_minus_utc_on(year: int, month: int, day: int) -> float:
    return _erfa_dat(year, month, day, 0.0)


def _erfa_dat(year: int, month: int, day: int, fraction: float) -> float:
    """TAI-UTC (s) from ERFA, imported here so that importing cistrack does not load it; ERFA's
    'dubious year' warning (before 1960, years after its table) is expected and silenced."""
    import warnings

    import erfa

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        return float(erfa.dat(year, month, day, fraction))


def elapsed_seconds(epoch: datetime, when: datetime) -> float:
    """Elapsed SI seconds from the UTC instant ``epoch`` to the UTC label ``when`` (negative
    before it): the clock difference plus the leap seconds between them."""
    clock = (when - epoch).total_seconds()
    leap = leap_seconds(epoch, when)
    return clock if leap == 0.0 else clock + leap


def utc_to_tu(epoch: datetime, when: datetime) -> float:
    """Nondimensional time t (TU since ``epoch``, elapsed) of the UTC label ``when``."""
    return elapsed_seconds(epoch, when) / TU_S


def utc_after(epoch: datetime, seconds: float) -> datetime:
    """UTC label ``seconds`` elapsed SI seconds after the UTC instant ``epoch`` (the inverse of
    :func:`elapsed_seconds`, to the microsecond).

    An instant inside a leap second (23:59:60.x) is given as 23:59:59.999999 of that day, the last
    label before it: the label then reads up to 1 s early, and never later than the next one.
    """
    clock = epoch + timedelta(seconds=seconds)
    leap = leap_seconds(epoch, clock)
    if leap == 0.0:
        return clock
    label = epoch + timedelta(seconds=seconds - leap)
    if abs(leap_seconds(epoch, label) - leap) < 0.5:
        return label
    # Inside a leap second: the midnight it ends lies between the two guesses.
    later = max(clock, label)
    midnight = (later.astimezone(timezone.utc) if later.tzinfo else later).replace(hour=0, minute=0, second=0,
                                                                                    microsecond=0)
    return midnight - timedelta(microseconds=1)


def grid_leap_seconds(epoch: datetime, first: datetime, step: timedelta, n: int) -> np.ndarray | None:
    """Leap seconds (s, (n,)) from ``epoch`` to each UTC label ``first + k * step`` of a grid
    (k = 0 .. n-1): what its clock times since ``epoch`` miss of elapsed time. None when no leap
    second lies between the epoch and any of them (TAI-UTC only grows, so the ends tell)."""
    if n <= 0 or (leap_seconds(epoch, first) == 0.0 and leap_seconds(epoch, first + (n - 1) * step) == 0.0):
        return None
    return np.array([leap_seconds(epoch, first + k * step) for k in range(n)])


def tu_to_utc(epoch: datetime, t: float) -> datetime:
    """UTC label of nondimensional time t (TU elapsed since ``epoch``); see :func:`utc_after`."""
    return utc_after(epoch, float(t) * TU_S)
