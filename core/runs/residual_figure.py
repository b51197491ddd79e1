"""The residual figure of a filter run: ``residuals.svg`` in its results directory.

Drawn from what ``steps.parquet`` holds (:mod:`cistrack.evaluation.residuals`): for each update,
``res_NAME_UNIT``, the observation minus the measurement the filter's prior predicted, and
``sd_NAME_UNIT``, the residual's predicted 1-sigma (the square root of the diagonal of the
innovation covariance S = P_zz + R); UNIT is arcsec for an angle (azimuth/elevation, right
ascension/declination), km for a range.

The figure has one panel per site and measured component, top to bottom (a site's azimuth and
elevation, or right ascension and declination, next to each other), sharing the time axis (days
since the scenario epoch): the residuals as dots, the predicted 1-sigma and 3-sigma bands around
zero where the table has ``sd_`` values, and a residual beyond its 3-sigma circled in red; a panel
whose first residuals dwarf the last (a filter converging) has a symmetric log axis. A step's
site is its measurement's (``measurement_index`` into the run's measurements); a step of several
sites at one time holds the first measurement's residuals, so it counts for that site.

The SVG is written as text (no plotting library: importing and laying out one cost more than the
rest of a short run). Each residual's marker carries its values, ``data-days`` and
``data-value``, as the shortest text that reads back as the same float, in the group whose id is
the panel's :attr:`ResidualPanel.gid`; each band (``class="band-3-sigma"``, ``"band-1-sigma"``)
carries the predicted 1-sigma it was drawn from, ``data-sd``; each panel is a ``<g class="panel">``.
"""
from __future__ import annotations

import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cistrack.results.store import RESIDUALS_FIGURE, STEPS

__all__ = ["FIGURE", "ResidualPanel", "residual_panels", "residual_figure", "write_residual_figure",
           "write_run_residual_figure"]

FIGURE = RESIDUALS_FIGURE
"""The figure's file name in a run's results directory."""
GAP_DAYS = 0.25
"""The bands are not drawn across a time without updates longer than this (between passes)."""
LINEAR_SPAN = 20.0
"""A panel whose largest residual or 3-sigma exceeds this many times the typical one is drawn on a
symmetric log axis (see :class:`_YAxis`)."""

_WIDTH, _LEFT, _RIGHT = 800.0, 84.0, 16.0   # px: the figure, the margins beside the panels
_TOP, _PANEL, _GAP, _BOTTOM = 70.0, 150.0, 40.0, 52.0  # px: above the first panel title, a panel, between, below
_BLUE, _RED, _BAND3, _BAND1, _INK = "#1f77b4", "#d62728", "#e0e0e0", "#b8b8b8", "#666666"


@dataclass(frozen=True)
class ResidualPanel:
    """One panel: the residuals of component ``name`` measured from ``site``.

    Attributes
    ----------
    site : str               the site key ("" = the sensor's own site)
    name : str               the component ("azimuth", "right_ascension", ...)
    unit : str               "arcsec", or "km" for a range
    days : (n,) float        the updates' times, days since the scenario epoch
    residual : (n,) float    observation minus predicted measurement (``unit``)
    sd : (n,) float          the predicted 1-sigma of each residual (``unit``; NaN where unknown)
    """

    site: str
    name: str
    unit: str
    days: np.ndarray
    residual: np.ndarray
    sd: np.ndarray

    @property
    def label(self) -> str:
        """The panel's axis label, e.g. ``"elevation (arcsec)"``."""
        return f"{self.name.replace('_', ' ')} ({self.unit})"

    @property
    def gid(self) -> str:
        """The id of the residuals' group in the SVG: ``residuals-<site>-<name>`` (site "sensor"
        for the sensor's own, characters other than letters, digits, ``_.-`` as ``_``)."""
        return re.sub(r"[^A-Za-z0-9_.-]", "_", f"residuals-{self.site or 'sensor'}-{self.name}")


def _column(steps, name: str) -> np.ndarray:
    """Column ``name`` of the pyarrow table ``steps`` as (num_rows,) floats (NaN for missing values).

    Read from the Arrow buffers of a numeric column: pyarrow's own ``to_numpy`` imports pandas
    (a third of a second) and its ``cast`` pyarrow.compute."""
    if name not in steps.column_names:
        return np.full(steps.num_rows, np.nan)
    parts = [_chunk_floats(chunk) for chunk in steps.column(name).chunks]
    return np.concatenate(parts) if parts else np.full(steps.num_rows, np.nan)


_NUMERIC = {"double": "<f8", "float": "<f4", "int64": "<i8", "int32": "<i4", "int16": "<i2", "int8": "i1",
            "uint64": "<u8", "uint32": "<u4", "uint16": "<u2", "uint8": "u1"}
"""numpy's dtype of each numeric Arrow type (by its name), as Arrow lays its values out."""


def _chunk_floats(arr) -> np.ndarray:
    """One pyarrow array of integers or floats as (len,) floats, NaN where null."""
    dtype = _NUMERIC.get(str(arr.type))
    buffers = arr.buffers()
    if dtype is None or len(buffers) != 2 or buffers[1] is None:
        return np.array([np.nan if v is None else float(v) for v in arr.to_pylist()], dtype=float)
    validity, data = buffers
    out = np.frombuffer(data, dtype=dtype, count=len(arr) + arr.offset)[arr.offset:].astype(float)
    if validity is not None and arr.null_count:
        bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
        out[~bits[arr.offset:arr.offset + len(arr)].astype(bool)] = np.nan
    return out


def _components(names: list[str]) -> list[tuple[str, str]]:
    """(name, unit) of every ``res_NAME_UNIT`` column among the column ``names``, in their order."""
    out = []
    for col in names:
        for unit in ("arcsec", "km"):
            if col.startswith("res_") and col.endswith(f"_{unit}"):
                out.append((col[len("res_"):-len(unit) - 1], unit))
    return out


def residual_panels(steps, measurements=None) -> list[ResidualPanel]:
    """The panels of the step table ``steps`` (a pyarrow Table with the columns of
    :mod:`cistrack.results.step_table`): per site (in order of first residual), each component
    with at least one residual there. ``measurements`` (the run's
    :class:`~cistrack.model.measurement.MeasurementSet`) gives each step's site; without it every
    step counts for the sensor's own site ("")."""
    index = _column(steps, "measurement_index")
    days = _column(steps, "t_days")
    site_of = (lambda i: measurements.site_at(int(i))) if measurements is not None else (lambda i: "")
    sites = np.array([site_of(i) if np.isfinite(i) and i >= 0 else "" for i in index], dtype=object)
    panels = []
    for name, unit in _components(steps.column_names):
        res, sd = _column(steps, f"res_{name}_{unit}"), _column(steps, f"sd_{name}_{unit}")
        for site in dict.fromkeys(sites[np.isfinite(res)].tolist()):
            rows = np.isfinite(res) & (sites == site)
            panels.append(ResidualPanel(site, name, unit, days[rows], res[rows], sd[rows]))
    order = list(dict.fromkeys(p.site for p in panels))
    return sorted(panels, key=lambda p: order.index(p.site))  # stable: components keep table order


def _site_name(site: str, sensor: str) -> str:
    return f"site {site}" if site else (f"sensor '{sensor}'" if sensor else "the sensor")


def _esc(text: str) -> str:
    """``text`` as SVG character data or an attribute value."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def _text(x: float, y: float, text: str, size: float, anchor: str = "start", extra: str = "") -> str:
    return (f'<text x="{x:.1f}" y="{y:.1f}" font-size="{size:g}" text-anchor="{anchor}"{extra}>'
            f"{_esc(text)}</text>")


def _nice_ticks(lo: float, hi: float, count: int = 6) -> list[float]:
    """Round tick values (1, 2, 2.5 or 5 times a power of ten apart) within [lo, hi]."""
    raw = (hi - lo) / max(count - 1, 1)
    if not raw > 0:
        return [lo]
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * power >= raw)
    first = math.ceil(lo / step - 1e-9)
    ticks = [k * step for k in range(first, math.floor(hi / step + 1e-9) + 1)]
    return [0.0 if abs(t) < step * 1e-9 else t for t in ticks]


def _tick_label(v: float) -> str:
    return f"{float(f'{v:.10g}'):g}"


class _XAxis:
    """The shared time axis: days since the epoch to px."""

    def __init__(self, panels: list[ResidualPanel]):
        days = np.concatenate([p.days for p in panels])
        lo, hi = float(np.min(days)), float(np.max(days))
        pad = 0.03 * (hi - lo) if hi > lo else 0.5
        self.lo, self.hi = lo - pad, hi + pad
        self.ticks = _nice_ticks(self.lo, self.hi, 8)

    def px(self, days) -> np.ndarray:
        """(n,) px of ``days``."""
        return _LEFT + (np.asarray(days, dtype=float) - self.lo) / (self.hi - self.lo) * (_WIDTH - _LEFT - _RIGHT)


class _YAxis:
    """One panel's value axis, symmetric about zero: linear, or, when the largest residual or
    3-sigma exceeds :data:`LINEAR_SPAN` times the typical one (the median of both), a symmetric log
    axis linear within the typical size: the first updates of a filter that converges are orders of
    magnitude larger than the last, and would flatten them into a line."""

    def __init__(self, size: np.ndarray, band: np.ndarray, top: float):
        values = np.concatenate([size, band])
        values = values[np.isfinite(values) & (values > 0)]
        largest = float(values.max()) if values.size else 1.0
        typical = float(np.median(values)) if values.size else 1.0
        self.linthresh = typical if largest > LINEAR_SPAN * typical else None
        self.top = top
        if self.linthresh is None:
            ticks = _nice_ticks(-1.08 * largest, 1.08 * largest, 5)
            self.limit = max(1.08 * largest, abs(ticks[0]), abs(ticks[-1]))
            self.ticks = ticks
        else:
            self.limit = self._log(1.15 * largest)
            decades = range(math.ceil(math.log10(typical)), math.floor(math.log10(largest)) + 1)
            self.ticks = [0.0] + [s * 10.0 ** k for k in decades for s in (1.0, -1.0)]

    def _log(self, v):
        """The symmetric-log coordinate of ``v`` (linear within the threshold, log10 decades beyond)."""
        a = np.abs(v) / self.linthresh
        return np.sign(v) * np.where(a <= 1.0, a, 1.0 + np.log10(np.maximum(a, 1.0)))

    def px(self, v) -> np.ndarray:
        """(n,) px of the values ``v`` (``unit``)."""
        u = np.asarray(v, dtype=float)
        u = u / self.limit if self.linthresh is None else self._log(u) / self.limit
        return self.top + (1.0 - u) * _PANEL / 2


def _segments(t: np.ndarray, sd: np.ndarray) -> list[np.ndarray]:
    """Index runs of the time-sorted updates over which a band is drawn: consecutive finite ``sd``
    values, not across a gap in ``t`` longer than :data:`GAP_DAYS`."""
    ok = np.isfinite(sd)
    breaks = np.flatnonzero((np.diff(t) > GAP_DAYS) | ~ok[1:] | ~ok[:-1]) + 1
    return [run for run in np.split(np.arange(t.size), breaks) if ok[run].all() and run.size]


def _bands(x: _XAxis, y: _YAxis, t: np.ndarray, sd: np.ndarray) -> list[str]:
    """The 3-sigma band, then the 1-sigma band (one closed path per segment of updates)."""
    out = []
    for k, cls, colour in ((3.0, "band-3-sigma", _BAND3), (1.0, "band-1-sigma", _BAND1)):
        paths = []
        for run in _segments(t, sd):
            xs = x.px(t[run])
            up, down = y.px(k * sd[run]), y.px(-k * sd[run])
            pts = [*zip(xs, up), *zip(xs[::-1], down[::-1])]
            paths.append("M" + " L".join(f"{a:.2f},{b:.2f}" for a, b in pts) + " Z")
        sds = " ".join(repr(float(v)) for v in sd)
        out.append(f'<g class="{cls}" fill="{colour}" data-sd="{sds}">'
                   + "".join(f'<path d="{d}"/>' for d in paths) + "</g>")
    return out


def _axes(x: _XAxis, y: _YAxis, panel: ResidualPanel, last: bool) -> list[str]:
    """The frame, grid, ticks and labels of one panel (tick labels of time under the last one)."""
    left, right, top, bottom = _LEFT, _WIDTH - _RIGHT, y.top, y.top + _PANEL
    out = [f'<rect x="{left:.1f}" y="{top:.1f}" width="{right - left:.1f}" height="{_PANEL:.1f}" '
           f'fill="none" stroke="#000000" stroke-width="0.8"/>']
    for v in y.ticks:
        py = float(y.px(v))
        out.append(f'<line x1="{left:.1f}" y1="{py:.2f}" x2="{right:.1f}" y2="{py:.2f}" stroke="#b0b0b0" '
                   f'stroke-width="0.6" opacity="0.6"/>')
        out.append(_text(left - 5, py + 3.5, _tick_label(v), 10, "end"))
    for v in x.ticks:
        px = float(x.px(v))
        out.append(f'<line x1="{px:.2f}" y1="{top:.1f}" x2="{px:.2f}" y2="{bottom:.1f}" stroke="#b0b0b0" '
                   f'stroke-width="0.6" opacity="0.6"/>')
        if last:
            out.append(_text(px, bottom + 14, _tick_label(v), 10, "middle"))
    mid = top + _PANEL / 2
    out.append(_text(16, mid, panel.label, 11, "middle", f' transform="rotate(-90 16 {mid:.1f})"'))
    if y.linthresh is not None:
        out.append(_text(right - 4, bottom - 5, f"linear within +-{y.linthresh:.3g}, logarithmic beyond", 8,
                         "end", f' fill="{_INK}"'))
    return out


def _points(x: _XAxis, y: _YAxis, panel: ResidualPanel, t, r, sd) -> tuple[list[str], int]:
    """The residuals' markers (group ``panel.gid``) and the circles of those beyond 3-sigma, and
    how many are beyond."""
    dots = "".join(f'<circle cx="{a:.2f}" cy="{b:.2f}" r="2.4" data-days="{d!r}" data-value="{v!r}"/>'
                   for a, b, d, v in zip(x.px(t), y.px(r), t.tolist(), r.tolist()))
    out = [f'<g id="{panel.gid}" fill="{_BLUE}">{dots}</g>']
    beyond = np.isfinite(sd) & (np.abs(r) > 3 * sd)
    if beyond.any():
        rings = "".join(f'<circle cx="{a:.2f}" cy="{b:.2f}" r="4"/>'
                        for a, b in zip(x.px(t[beyond]), y.px(r[beyond])))
        out.append(f'<g class="beyond-3-sigma" fill="none" stroke="{_RED}" stroke-width="1">{rings}</g>')
    return out, int(beyond.sum())


def _panel(x: _XAxis, panel: ResidualPanel, top: float, sensor: str, last: bool) -> tuple[list[str], set[str]]:
    """One panel's SVG elements, and the legend entries it shows."""
    order = np.argsort(panel.days, kind="stable")
    t, r, sd = panel.days[order], panel.residual[order], panel.sd[order]
    has_sd = np.isfinite(sd)
    y = _YAxis(np.abs(r), 3 * sd[has_sd], top)
    out = _bands(x, y, t, sd) if has_sd.any() else []
    out += _axes(x, y, panel, last)
    zero = float(y.px(0.0))
    out.append(f'<line x1="{_LEFT:.1f}" y1="{zero:.2f}" x2="{_WIDTH - _RIGHT:.1f}" y2="{zero:.2f}" '
               f'stroke="{_INK}" stroke-width="0.8"/>')
    dots, beyond = _points(x, y, panel, t, r, sd)
    out += dots
    rms = float(np.sqrt(np.mean(r ** 2)))
    out.append(_text(_WIDTH - _RIGHT, top - 6, f"{panel.label}: RMS {rms:.3g} {panel.unit}, {r.size} updates, "
                     f"{beyond} beyond 3 sigma", 11, "end"))
    out.append(_text(_LEFT + 6, top + 13, _site_name(panel.site, sensor), 10))
    shown = {"residual"} | ({"band"} if has_sd.any() else set()) | ({"beyond"} if beyond else set())
    return out, shown


def _legend(shown: set[str]) -> list[str]:
    """The legend row above the first panel: the entries some panel shows."""
    entries = [("band", f'<rect width="18" height="9" y="-8" fill="{_BAND3}"/>', "predicted 3 sigma"),
               ("band", f'<rect width="18" height="9" y="-8" fill="{_BAND1}"/>', "predicted 1 sigma"),
               ("residual", f'<circle cx="9" cy="-3.5" r="2.4" fill="{_BLUE}"/>', "residual"),
               ("beyond", f'<circle cx="9" cy="-3.5" r="4" fill="none" stroke="{_RED}"/>', "beyond 3 sigma")]
    out, at = [], _LEFT
    for key, mark, label in entries:
        if key in shown:
            out.append(f'<g transform="translate({at:.1f} {_TOP - 26:.1f})">{mark}'
                       f'{_text(24, 0, label, 10)}</g>')
            at += 40 + 6.2 * len(label)
    return out


def residual_figure(panels: list[ResidualPanel], title: str = "", epoch: str = "", sensor: str = "") -> str:
    """The SVG document (text) of ``panels`` (at least one), one panel each, top to bottom;
    ``epoch`` (UTC text) names the time axis' zero, ``sensor`` the sensor's own site."""
    x = _XAxis(panels)
    height = _TOP + len(panels) * _PANEL + (len(panels) - 1) * _GAP + _BOTTOM
    body, shown = [], set()
    for i, panel in enumerate(panels):
        elements, more = _panel(x, panel, _TOP + i * (_PANEL + _GAP), sensor, i == len(panels) - 1)
        body.append('<g class="panel">' + "\n".join(elements) + "</g>")
        shown |= more
    heading = (title + ": " if title else "") + "filter residuals against the predicted measurement"
    body.append(_text(_WIDTH / 2, 20, heading, 13, "middle"))
    body += _legend(shown)
    body.append(_text((_LEFT + _WIDTH - _RIGHT) / 2, height - 12, "days since " + (epoch or "the scenario epoch"),
                      11, "middle"))
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{_WIDTH:g}" height="{height:g}" '
            f'viewBox="0 0 {_WIDTH:g} {height:g}" font-family="DejaVu Sans, Arial, sans-serif">\n'
            f'<rect width="100%" height="100%" fill="#ffffff"/>\n' + "\n".join(body) + "\n</svg>\n")


def _read_steps(path: Path):
    """The columns of ``path`` (a step table) the figure draws, as a pyarrow Table."""
    import pyarrow.parquet as pq  # ParquetFile, not read_table: that imports pyarrow.dataset and pandas

    f = pq.ParquetFile(path)
    names = f.schema_arrow.names
    keep = [c for c in names if c in ("measurement_index", "t_days") or c.startswith(("res_", "sd_"))]
    return f.read(columns=keep)


def write_residual_figure(directory: str | Path, measurements=None, title: str = "", epoch: str = "",
                          sensor: str = "") -> Path | None:
    """Draw the residuals of the run in ``directory`` (its ``steps.parquet``) into
    ``directory/residuals.svg`` and return that path; None, with any earlier figure removed, when
    the table holds no residual. ``measurements``, ``title``, ``epoch``, ``sensor``: see
    :func:`residual_panels` and :func:`residual_figure`."""
    from cistrack.results.atomic_files import write_text_atomic

    d = Path(directory)
    panels = residual_panels(_read_steps(d / "steps.parquet"), measurements)
    if not panels:
        (d / FIGURE).unlink(missing_ok=True)
        return None
    write_text_atomic(d / FIGURE, residual_figure(panels, title, epoch, sensor))
    return d / FIGURE


def write_run_residual_figure(ctx, directory: Path, status: str) -> Path | None:
    """The residual figure of the run ``ctx`` (a :class:`~cistrack.runs.run_context.RunContext`)
    that has written its results into ``directory``, drawn when its steps were merged and it was
    not interrupted (an earlier run's figure is removed otherwise). A failure to write (a full disk)
    is a warning on the ``cistrack`` logger: the run's results stand without the figure."""
    d = Path(directory)
    if status == "interrupted" or not (d / STEPS).is_file():
        (d / FIGURE).unlink(missing_ok=True)
        return None
    from cistrack import units

    try:
        return write_residual_figure(d, ctx.measurements, ctx.run_id, units.format_utc(ctx.epoch)[:19] + "Z",
                                     ctx.scenario.components["sensor"].name)
    except OSError as exc:
        logging.getLogger("cistrack").warning(f"{d / FIGURE}: the residual figure was not written ({exc})")
        return None
