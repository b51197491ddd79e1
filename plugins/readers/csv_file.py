"""Reading and writing ground-telescope measurements as CSV (format: docs/measurements.md).

Registered as reader ``"csv"`` (suffix ``.csv``). One row per measurement; a header row names
the columns (any order)::

    time_utc,azimuth_deg,elevation_deg[,range_km][,sigma_azimuth_arcsec][,sigma_elevation_arcsec][,sigma_range_km][,site]

``site`` (optional) names the observing site of the row: a key of the reader's ``sites``
parameter or an MPC observatory code of the bundled table. Times increase; rows of different
sites may share a time (a filter takes them in one step).

Lines starting with ``#`` and blank lines are ignored. Every invalid row is reported with its
line number in one :class:`~cistrack.errors.MeasurementError` naming the file; nothing is
dropped silently.
"""
from __future__ import annotations

import csv
import math
from datetime import datetime
from os import PathLike
from pathlib import Path

import numpy as np

from cistrack.interfaces.component import check_positive
from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.interfaces import Reader
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.sites import Site
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S, format_utc, parse_utc, tu_to_utc

from .decimal_units import from_rad, plain_float, to_rad
from .site_params import parse_sites, resolve_site

__all__ = ["CsvReader", "read_measurements", "write_measurements", "REQUIRED_COLUMNS", "OPTIONAL_COLUMNS"]

REQUIRED_COLUMNS = ("time_utc", "azimuth_deg", "elevation_deg")
OPTIONAL_COLUMNS = ("range_km", "sigma_azimuth_arcsec", "sigma_elevation_arcsec", "sigma_range_km", "site")
_MAX_REPORTED = 25


def _number(text: str, column: str) -> float:
    try:
        v = plain_float(text)
    except ValueError:
        raise ValueError(f"{column} {text!r} is not a number") from None
    if not math.isfinite(v):
        raise ValueError(f"{column} is {text.strip()} (must be finite)")
    return v


def read_measurements(path: str | PathLike, epoch: str | datetime, *, sigma_arcsec: float = 1.5,
                      range_alpha: float = 0.05, include_range: bool = True,
                      sites: dict[str, Site] | None = None) -> MeasurementSet:
    """Read a measurement CSV into a :class:`MeasurementSet` (times TU since ``epoch``).

    Parameters
    ----------
    path : CSV file (format in docs/measurements.md).
    epoch : the scenario's UTC epoch (ISO-8601 string or datetime); t = 0 there.
    sigma_arcsec : angle sigma (arcsec) for rows without ``sigma_azimuth_arcsec`` /
        ``sigma_elevation_arcsec`` (missing column or empty cell).
    range_alpha : range sigma = range_alpha x range for rows without ``sigma_range_km``.
    include_range : keep the ``range_km`` column when the file has one.
    sites : explicit sites by key for the ``site`` column (other keys: MPC observatory codes).

    Returns a set named ("azimuth", "elevation"[, "range"]): values in rad, rad, LU;
    sigmas likewise. Raises MeasurementError naming the file and every bad line.
    """
    p = Path(path)
    try:
        ep = parse_utc(epoch)
    except ValueError as exc:
        raise MeasurementError(f"{p}: epoch {epoch!r} is not an ISO-8601 UTC time") from exc
    if not (sigma_arcsec > 0 and range_alpha > 0):
        raise MeasurementError(f"{p}: default sigma_arcsec and range_alpha must be > 0")
    try:
        lines = p.read_text(encoding="utf-8-sig").splitlines()  # a leading byte-order mark is dropped
    except OSError as exc:
        raise MeasurementError(f"cannot read measurement file {p}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise MeasurementError(f"{p}: not a UTF-8 text file ({exc.reason})") from exc

    rows = [(i + 1, line) for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise MeasurementError(f"{p}: no header row (expected columns {', '.join(REQUIRED_COLUMNS)})")
    header_line, header_text = rows[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    unknown = [c for c in header if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    dupes = sorted({c for c in header if header.count(c) > 1})
    if missing or unknown or dupes:
        parts = []
        if missing:
            parts.append(f"missing column(s) {missing}")
        if unknown:
            parts.append(f"unknown column(s) {unknown}")
        if dupes:
            parts.append(f"repeated column(s) {dupes}")
        raise MeasurementError(
            f"{p}, line {header_line}: bad header: {'; '.join(parts)}; allowed columns: "
            f"{', '.join(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)}")
    if "sigma_range_km" in header and "range_km" not in header:
        raise MeasurementError(f"{p}, line {header_line}: sigma_range_km given without range_km")
    col = {name: header.index(name) for name in header}
    has_range = "range_km" in col

    errors: list[str] = []
    times, values, sigmas, row_sites = [], [], [], []
    site_table: dict[str, Site] = {}
    last_t, last_line = -math.inf, 0
    sites_at_t: set = set()  # sites of the rows at last_t: one time, several sites, one row each
    for line_no, text in rows[1:]:
        cells = [c.strip() for c in next(csv.reader([text]))]
        if len(cells) != len(header):
            errors.append(f"line {line_no}: {len(cells)} fields (columns), the header has {len(header)}")
            continue
        try:
            try:
                t_utc = parse_utc(cells[col["time_utc"]])
            except ValueError:
                raise ValueError(f"time_utc {cells[col['time_utc']]!r} is not an ISO-8601 UTC time") from None
            t = (t_utc - ep).total_seconds() / TU_S
            az = _number(cells[col["azimuth_deg"]], "azimuth_deg")
            el = _number(cells[col["elevation_deg"]], "elevation_deg")
            if not 0.0 <= az < 360.0:
                raise ValueError(f"azimuth_deg {az} is outside [0, 360)")
            if not -90.0 <= el <= 90.0:
                raise ValueError(f"elevation_deg {el} is outside [-90, 90]")
            row_sig = []
            for name in ("sigma_azimuth_arcsec", "sigma_elevation_arcsec"):
                cell = cells[col[name]] if name in col else ""
                s = _number(cell, name) if cell else sigma_arcsec
                if s <= 0:
                    raise ValueError(f"{name} {s} must be > 0")
                row_sig.append(to_rad(cell, "arcsec") if cell else s * ARCSEC_RAD)
            row_val = [to_rad(cells[col["azimuth_deg"]], "deg"), to_rad(cells[col["elevation_deg"]], "deg")]
            if has_range:
                rng = _number(cells[col["range_km"]], "range_km")
                if rng <= 0:
                    raise ValueError(f"range_km {rng} must be > 0")
                cell = cells[col["sigma_range_km"]] if "sigma_range_km" in col else ""
                srng = _number(cell, "sigma_range_km") if cell else range_alpha * rng
                if srng <= 0:
                    raise ValueError(f"sigma_range_km {srng} must be > 0")
                row_val.append(rng / LU_KM)
                row_sig.append(srng / LU_KM)
            if "site" in col:
                key = cells[col["site"]]
                if key not in site_table:
                    try:
                        site_table[key] = resolve_site(key, sites or {})
                    except MeasurementError as exc:
                        raise ValueError(f"site: {exc}") from None
        except ValueError as exc:
            errors.append(f"line {line_no}: {exc}")
            continue
        site_key = cells[col["site"]] if "site" in col else None
        if t < last_t or (t == last_t and (site_key is None or site_key in sites_at_t)):
            why = "is not after" if site_key is None or t < last_t else f"repeats site {site_key!r} at the time of"
            errors.append(f"line {line_no}: time_utc {cells[col['time_utc']]!r} {why} line {last_line}")
            continue
        sites_at_t = sites_at_t | {site_key} if t == last_t else {site_key}
        last_t, last_line = t, line_no
        times.append(t)
        values.append(row_val)
        sigmas.append(row_sig)
        if "site" in col:
            row_sites.append(cells[col["site"]])

    if errors:
        shown = "\n  ".join(errors[:_MAX_REPORTED])
        more = f"\n  ... and {len(errors) - _MAX_REPORTED} more" if len(errors) > _MAX_REPORTED else ""
        raise MeasurementError(f"{p}: {len(errors)} invalid row(s):\n  {shown}{more}")
    if not times:
        raise MeasurementError(f"{p}: the file has a header but no measurements")

    names = ("azimuth", "elevation", "range") if has_range else ("azimuth", "elevation")
    mset = MeasurementSet(np.array(times), np.array(values), np.array(sigmas), names,
                          {"source": str(p), "epoch": format_utc(ep)},
                          sites=np.array(row_sites) if "site" in col else None,
                          kinds=np.full(len(times), "azel"), site_table=site_table)
    if has_range and not include_range:
        mset = mset.without("range")
    return mset


def write_measurements(path: str | PathLike, mset: MeasurementSet, epoch: str | datetime) -> None:
    """Write ``mset`` (names ("azimuth", "elevation"[, "range"]), rad and LU, times TU since
    ``epoch``) as a measurement CSV with per-row sigmas. Times are written to the microsecond,
    angles in degrees and ranges in km with full double precision."""
    names = tuple(mset.names)
    if names not in (("azimuth", "elevation"), ("azimuth", "elevation", "range")) or (
            mset.kinds is not None and set(mset.kinds.tolist()) != {"azel"}):
        raise MeasurementError(
            f"write_measurements: expected components ('azimuth', 'elevation'[, 'range']), got {names}")
    try:
        ep = parse_utc(epoch)
    except ValueError as exc:
        raise MeasurementError(f"write_measurements: epoch {epoch!r} is not an ISO-8601 UTC time") from exc
    has_range = len(names) == 3
    header = ["time_utc", "azimuth_deg", "elevation_deg"]
    if has_range:
        header.append("range_km")
    header += ["sigma_azimuth_arcsec", "sigma_elevation_arcsec"]
    if has_range:
        header.append("sigma_range_km")
    if mset.sites is not None:
        header.append("site")
    az_deg = np.degrees(np.mod(mset.values[:, 0], 2.0 * np.pi))
    az_deg = np.where(az_deg >= 360.0, 0.0, az_deg)
    p = Path(path)
    with p.open("w", encoding="utf-8", newline="") as fh:
        fh.write("# cistrack measurements (format: docs/measurements.md)\n")
        fh.write(f"# epoch: {format_utc(ep)}\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        for k in range(len(mset)):
            az = float(np.mod(mset.values[k, 0], 2.0 * np.pi))
            row = [format_utc(tu_to_utc(ep, mset.times[k])), from_rad(az, "deg"),
                   from_rad(float(mset.values[k, 1]), "deg")]
            if has_range:
                row.append(repr(float(mset.values[k, 2] * LU_KM)))
            row += [from_rad(float(mset.sigmas[k, j]), "arcsec") for j in (0, 1)]
            if has_range:
                row.append(repr(float(mset.sigmas[k, 2] * LU_KM)))
            if mset.sites is not None:
                row.append(str(mset.sites[k]))
            w.writerow(row)


class CsvReader(Reader):
    """cistrack's own CSV of azimuth/elevation (docs/measurements.md).

    Parameters
    ----------
    sigma_arcsec : float
        Angle sigma (arcsec) for rows without sigma columns.
    range_alpha : float
        Range sigma as a fraction of the range for rows without ``sigma_range_km``.
    include_range : bool
        Keep the ``range_km`` column when the file has one.
    sites : dict or None
        Explicit sites by key for the ``site`` column: KEY -> {latitude_deg, longitude_deg,
        height_m[, name]}; other keys are MPC observatory codes.
    """

    suffixes = (".csv",)

    def __init__(self, sigma_arcsec: float = 1.5, range_alpha: float = 0.05, include_range: bool = True,
                 sites: dict | None = None) -> None:
        self.sigma_arcsec = check_positive(self, "sigma_arcsec", sigma_arcsec)
        self.range_alpha = check_positive(self, "range_alpha", range_alpha)
        if not isinstance(include_range, bool):
            self._fail("include_range", include_range, "must be true or false")
        self.include_range = include_range
        self._sites = parse_sites(self, sites)
        self.sites = sites

    def read(self, path, epoch) -> MeasurementSet:
        return read_measurements(path, epoch, sigma_arcsec=self.sigma_arcsec, range_alpha=self.range_alpha,
                                 include_range=self.include_range, sites=self._sites)

    def write(self, path, measurements, epoch) -> None:
        write_measurements(path, measurements, epoch)


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "csv", CsvReader)
