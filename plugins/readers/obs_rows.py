"""Building a MeasurementSet from parsed observation rows, shared by the readers.

Each reader parses its syntax into :class:`ObsRow` (time, two angles in rad, optional sigmas,
site key, type, and the line each came from) and hands them to :func:`build_set`, which sorts
by time, refuses two observations at the same time with both lines named, and fills the
per-measurement sites and types. Times are given as UTC datetimes.
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone

import numpy as np

from cistrack.model.measurement import KIND_NAMES, MeasurementSet
from cistrack.runs.observation_files import FieldError
from cistrack.astro.sites import Site
from cistrack.units import ARCSEC_RAD, TU_S, format_utc, parse_utc

__all__ = ["ObsRow", "build_set", "parse_epoch", "parse_iso_utc", "TIME_FIELD_HELP"]

TIME_FIELD_HELP = "an ISO-8601 UTC time such as 2026-03-01T03:40:00.000000Z"


@dataclass
class ObsRow:
    """One parsed observation: ``t`` UTC, angles (rad), sigmas (rad or None: reader default)."""

    t: datetime
    a: float
    b: float
    sigma_a: float | None
    sigma_b: float | None
    site: str
    kind: str
    line: int
    time_field: str


def parse_epoch(path, epoch) -> datetime:
    try:
        return parse_utc(epoch)
    except (ValueError, TypeError):
        from cistrack.errors import MeasurementError
        raise MeasurementError(f"{path}: epoch {epoch!r} is not an ISO-8601 UTC time") from None


def parse_iso_utc(text: str) -> datetime:
    """An ISO-8601 time that must be UTC ('Z', '+00:00' or no zone); ValueError otherwise."""
    s = text.strip()
    if not s or "T" not in s:
        raise ValueError("not " + TIME_FIELD_HELP)
    dt = parse_utc(s)
    if s[-1] not in "Z" and ("+" in s[10:] or s.count("-") > 2) and not s.endswith("+00:00"):
        raise ValueError("must be UTC (end in Z)")
    return dt.astimezone(timezone.utc)


def build_set(path, rows: list[ObsRow], epoch: datetime, site_table: dict[str, Site],
              sigma_arcsec: float, meta: dict | None = None) -> MeasurementSet:
    """The MeasurementSet of ``rows`` in time order (TU since ``epoch``)."""
    if not rows:
        raise FieldError(path, 1, "(observations)", "the file has no observations")
    rows = sorted(rows, key=lambda r: (r.t, r.line))
    for prev, cur in zip(rows, rows[1:]):
        if cur.t == prev.t:
            raise FieldError(path, cur.line, cur.time_field,
                             f"time {format_utc(cur.t)} repeats the observation of line {prev.line}; "
                             f"times must differ")
    kinds = {r.kind for r in rows}
    names = KIND_NAMES[rows[0].kind] if len(kinds) == 1 else ("angle_1", "angle_2")
    default = sigma_arcsec * ARCSEC_RAD
    times = np.array([(r.t - epoch).total_seconds() / TU_S for r in rows])
    values = np.array([[r.a, r.b] for r in rows])
    sigmas = np.array([[r.sigma_a if r.sigma_a is not None else default,
                        r.sigma_b if r.sigma_b is not None else default] for r in rows])
    used = {r.site for r in rows}
    return MeasurementSet(times, values, sigmas, names,
                          {"source": str(path), "epoch": format_utc(epoch), **(meta or {})},
                          sites=np.array([r.site for r in rows]), kinds=np.array([r.kind for r in rows]),
                          site_table={k: v for k, v in site_table.items() if k in used})
