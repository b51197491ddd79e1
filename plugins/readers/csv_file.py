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
from dataclasses import dataclass, field
from datetime import datetime
from os import PathLike
from pathlib import Path

import numpy as np

from cistrack.interfaces.component import check_range, check_sigma_arcsec, sigma_arcsec_problem
from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.interfaces import Reader
from cistrack.interfaces.reader import split_lines
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.sites import Site
from cistrack.units import ARCSEC_RAD, LU_KM, format_utc, parse_utc, tu_to_utc, utc_to_tu

from .ades_records import SMALLEST_PLAUSIBLE_ARCSEC
from .decimal_units import from_rad, plain_float, to_rad
from .obs_rows import say_below_horizon
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


def _parse_epoch(p: Path, epoch: str | datetime) -> datetime:
    try:
        return parse_utc(epoch)
    except ValueError as exc:
        raise MeasurementError(f"{p}: epoch {epoch!r} is not an ISO-8601 UTC time") from exc


def _data_lines(p: Path) -> list[tuple[int, str]]:
    """The file's non-blank, non-comment lines as (1-based line number, text)."""
    try:
        lines = split_lines(p.read_text(encoding="utf-8-sig"))  # a leading byte-order mark is dropped
    except OSError as exc:
        raise MeasurementError(f"cannot read measurement file {p}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise MeasurementError(f"{p}: not a UTF-8 text file ({exc.reason})") from exc
    return [(i + 1, line) for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]


def _header_problems(header: list[str]) -> list[str]:
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    unknown = [c for c in header if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    dupes = sorted({c for c in header if header.count(c) > 1})
    parts = []
    if missing:
        parts.append(f"missing column(s) {missing}")
    if unknown:
        parts.append(f"unknown column(s) {unknown}")
    if dupes:
        parts.append(f"repeated column(s) {dupes}")
    return parts


def _header_columns(p: Path, rows: list[tuple[int, str]]) -> dict[str, int]:
    """Column name -> index from the header row (the first of ``rows``); raises on a bad header."""
    if not rows:
        raise MeasurementError(f"{p}: no header row (expected columns {', '.join(REQUIRED_COLUMNS)})")
    header_line, header_text = rows[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    parts = _header_problems(header)
    if parts:
        raise MeasurementError(
            f"{p}, line {header_line}: bad header: {'; '.join(parts)}; allowed columns: "
            f"{', '.join(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)}")
    if "sigma_range_km" in header and "range_km" not in header:
        raise MeasurementError(f"{p}, line {header_line}: sigma_range_km given without range_km")
    return {name: header.index(name) for name in header}


def _say_tiny_sigmas(path, tiny: dict[str, list[float]]) -> None:
    """Warn (logger ``cistrack.readers``, once per column and file) of stated angle sigmas below
    1 milliarcsecond: arcseconds by the column's name, most likely degrees by mistake. They are used."""
    import logging

    for name, values in tiny.items():
        logging.getLogger("cistrack.readers").warning(
            f"{path}: column {name}: {len(values)} rows state an uncertainty below 1 milliarcsecond (the first "
            f"{values[0]:.3g} arcsec); the column is in arcseconds: are these degrees? They are used as given")


@dataclass
class _RowParser:
    """Turns the cells of one data row into (t [TU], values, sigmas) in rad/LU; collects sites."""

    col: dict[str, int]
    epoch: datetime
    sigma_arcsec: float
    range_alpha: float
    sites: dict[str, Site]
    site_table: dict[str, Site] = field(default_factory=dict)
    tiny: dict[str, list[float]] = field(default_factory=dict)  # column -> stated sigmas below 1 mas, arcsec

    def cell(self, cells: list[str], name: str) -> str:
        return cells[self.col[name]] if name in self.col else ""

    def parse(self, cells: list[str]) -> tuple[float, list[float], list[float]]:
        """Raises ValueError naming the first bad cell."""
        t = self._time(cells[self.col["time_utc"]])
        values, sigmas = self._angles(cells)
        if "range_km" in self.col:
            rng, srng = self._range(cells)
            values.append(rng / LU_KM)
            sigmas.append(srng / LU_KM)
        if "site" in self.col:
            self._resolve_site(cells[self.col["site"]])
        return t, values, sigmas

    def _time(self, text: str) -> float:
        from .obs_rows import LEAP_SECOND_PROBLEM, is_leap_second, year_problem

        if is_leap_second(text):
            raise ValueError(f"time_utc {text!r} {LEAP_SECOND_PROBLEM}")
        try:
            t_utc = parse_utc(text)
        except ValueError:
            raise ValueError(f"time_utc {text!r} is not an ISO-8601 UTC time") from None

        if year_problem(t_utc):
            raise ValueError(f"time_utc {text!r}: {year_problem(t_utc)}")
        return utc_to_tu(self.epoch, t_utc)  # elapsed: leap seconds counted

    def _angles(self, cells: list[str]) -> tuple[list[float], list[float]]:
        az_text, el_text = cells[self.col["azimuth_deg"]], cells[self.col["elevation_deg"]]
        az = _number(az_text, "azimuth_deg")
        el = _number(el_text, "elevation_deg")
        if not 0.0 <= az < 360.0:
            raise ValueError(f"azimuth_deg {az} is outside [0, 360)")
        if not -90.0 <= el <= 90.0:
            raise ValueError(f"elevation_deg {el} is outside [-90, 90]")
        sigmas = [self._angle_sigma(self.cell(cells, name), name)
                  for name in ("sigma_azimuth_arcsec", "sigma_elevation_arcsec")]
        return [to_rad(az_text, "deg"), to_rad(el_text, "deg")], sigmas

    def _angle_sigma(self, cell: str, name: str) -> float:
        s = _number(cell, name) if cell else self.sigma_arcsec
        problem = sigma_arcsec_problem(s)
        if problem:
            raise ValueError(f"{name} {s} {problem}")
        if cell and s < SMALLEST_PLAUSIBLE_ARCSEC:
            self.tiny.setdefault(name, []).append(s)
        return to_rad(cell, "arcsec") if cell else s * ARCSEC_RAD

    def _range(self, cells: list[str]) -> tuple[float, float]:
        """Range and its sigma in km."""
        rng = _number(cells[self.col["range_km"]], "range_km")
        if rng <= 0:
            raise ValueError(f"range_km {rng} must be > 0")
        cell = self.cell(cells, "sigma_range_km")
        srng = _number(cell, "sigma_range_km") if cell else self.range_alpha * rng
        if srng <= 0:
            raise ValueError(f"sigma_range_km {srng} must be > 0")
        return rng, srng

    def _resolve_site(self, key: str) -> None:
        if key not in self.site_table:
            try:
                self.site_table[key] = resolve_site(key, self.sites)
            except MeasurementError as exc:
                raise ValueError(f"site: {exc}") from None


@dataclass
class _TimeOrder:
    """Checks that times increase; rows at one time must name different sites."""

    last_t: float = -math.inf
    last_line: int = 0
    sites_at_t: set = field(default_factory=set)  # sites of the rows at last_t

    def problem(self, t: float, site_key: str | None, line_no: int, time_text: str) -> str | None:
        """The error for a row out of order (and leaves the state as it was), else None (and
        records the row)."""
        if t < self.last_t or (t == self.last_t and (site_key is None or site_key in self.sites_at_t)):
            why = "is not after" if site_key is None or t < self.last_t else f"repeats site {site_key!r} at the time of"
            return f"line {line_no}: time_utc {time_text!r} {why} line {self.last_line}"
        self.sites_at_t = self.sites_at_t | {site_key} if t == self.last_t else {site_key}
        self.last_t, self.last_line = t, line_no
        return None


def _raise_row_errors(p: Path, errors: list[str]) -> None:
    if errors:
        shown = "\n  ".join(errors[:_MAX_REPORTED])
        more = f"\n  ... and {len(errors) - _MAX_REPORTED} more" if len(errors) > _MAX_REPORTED else ""
        raise MeasurementError(f"{p}: {len(errors)} invalid row(s):\n  {shown}{more}")


def _parse_rows(rows: list[tuple[int, str]], parser: _RowParser, errors: list[str]):
    """Parse the data rows; bad ones go to ``errors``. Returns times, values, sigmas, row sites."""
    n_columns = len(parser.col)
    times, values, sigmas, row_sites = [], [], [], []
    order = _TimeOrder()
    for line_no, text in rows:
        cells = [c.strip() for c in next(csv.reader([text]))]
        if len(cells) != n_columns:
            errors.append(f"line {line_no}: {len(cells)} fields (columns), the header has {n_columns}")
            continue
        try:
            t, row_val, row_sig = parser.parse(cells)
        except ValueError as exc:
            errors.append(f"line {line_no}: {exc}")
            continue
        site_key = cells[parser.col["site"]] if "site" in parser.col else None
        problem = order.problem(t, site_key, line_no, cells[parser.col["time_utc"]])
        if problem:
            errors.append(problem)
            continue
        times.append(t)
        values.append(row_val)
        sigmas.append(row_sig)
        if site_key is not None:
            row_sites.append(site_key)
    return times, values, sigmas, row_sites


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
    ep = _parse_epoch(p, epoch)
    problems = [f"default sigma_arcsec {p_}" for p_ in [sigma_arcsec_problem(float(sigma_arcsec))] if p_]
    problems += [] if range_alpha > 0 else ["range_alpha must be > 0"]
    if problems:
        raise MeasurementError(f"{p}: {'; '.join(problems)} (got sigma_arcsec={sigma_arcsec!r}, "
                               f"range_alpha={range_alpha!r})")
    rows = _data_lines(p)
    col = _header_columns(p, rows)
    parser = _RowParser(col, ep, sigma_arcsec, range_alpha, sites or {})
    errors: list[str] = []
    times, values, sigmas, row_sites = _parse_rows(rows[1:], parser, errors)
    _raise_row_errors(p, errors)
    _say_tiny_sigmas(p, parser.tiny)
    if not times:
        raise MeasurementError(f"{p}: the file has a header but no measurements")
    say_below_horizon(p, [v[1] for v in values], [line for line, _ in rows[1:]])

    has_range = "range_km" in col
    names = ("azimuth", "elevation", "range") if has_range else ("azimuth", "elevation")
    mset = MeasurementSet(np.array(times), np.array(values), np.array(sigmas), names,
                          {"source": str(p), "epoch": format_utc(ep)},
                          sites=np.array(row_sites) if "site" in col else None,
                          kinds=np.full(len(times), "azel"), site_table=parser.site_table)
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
        self.sigma_arcsec = check_sigma_arcsec(self, "sigma_arcsec", sigma_arcsec)
        self.range_alpha = check_range(self, "range_alpha", range_alpha, 0.0, 1.0, lo_open=True)
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
