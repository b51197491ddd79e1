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

matplotlib is imported only when a figure is drawn (its object interface: no global backend is
changed).
"""
from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FIGURE", "ResidualPanel", "residual_panels", "residual_figure", "write_residual_figure",
           "write_run_residual_figure"]

FIGURE = "residuals.svg"
"""The figure's file name in a run's results directory."""
GAP_DAYS = 0.25
"""The bands are not drawn across a time without updates longer than this (between passes)."""
LINEAR_SPAN = 20.0
"""A panel whose largest residual or 3-sigma exceeds this many times the typical one is drawn on a
symmetric log axis (see :func:`_scale`)."""


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
    """Column ``name`` of the pyarrow table ``steps`` as floats (NaN for missing values)."""
    if name not in steps.column_names:
        return np.full(steps.num_rows, np.nan)
    return np.asarray(steps.column(name).to_numpy(zero_copy_only=False), dtype=float)


def _components(steps) -> list[tuple[str, str]]:
    """(name, unit) of every ``res_NAME_UNIT`` column of ``steps``, in table order."""
    out = []
    for col in steps.column_names:
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
    for name, unit in _components(steps):
        res, sd = _column(steps, f"res_{name}_{unit}"), _column(steps, f"sd_{name}_{unit}")
        for site in dict.fromkeys(sites[np.isfinite(res)].tolist()):
            rows = np.isfinite(res) & (sites == site)
            panels.append(ResidualPanel(site, name, unit, days[rows], res[rows], sd[rows]))
    order = list(dict.fromkeys(p.site for p in panels))
    return sorted(panels, key=lambda p: order.index(p.site))  # stable: components keep table order


def _site_name(site: str, sensor: str) -> str:
    return f"site {site}" if site else (f"sensor '{sensor}'" if sensor else "the sensor")


def _broken(t: np.ndarray, sd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``t`` and ``sd`` (sorted by time) with a NaN between two updates further apart than
    :data:`GAP_DAYS`, so that a band is not drawn across the time between passes."""
    gaps = np.flatnonzero(np.diff(t) > GAP_DAYS) + 1
    return np.insert(t, gaps, t[gaps - 1]), np.insert(sd, gaps, np.nan)


def _draw(ax, panel: ResidualPanel) -> None:
    """One panel on ``ax``: the 3-sigma and 1-sigma bands, zero, the residuals (beyond 3-sigma in red)."""
    order = np.argsort(panel.days)
    t, r, sd = panel.days[order], panel.residual[order], panel.sd[order]
    has_sd = np.isfinite(sd)
    if has_sd.any():
        bt, bsd = _broken(t, sd)
        ax.fill_between(bt, -3 * bsd, 3 * bsd, where=np.isfinite(bsd), color="0.88", lw=0, label="predicted 3 sigma")
        ax.fill_between(bt, -bsd, bsd, where=np.isfinite(bsd), color="0.72", lw=0, label="predicted 1 sigma")
    ax.axhline(0.0, color="0.4", lw=0.8)
    line, = ax.plot(t, r, "o", ms=3.5, color="tab:blue", label="residual")
    line.set_gid(panel.gid)
    out = has_sd & (np.abs(r) > 3 * sd)
    if out.any():
        ax.plot(t[out], r[out], "o", ms=5, mfc="none", color="tab:red", label="beyond 3 sigma")
    _scale(ax, np.abs(r), 3 * sd[has_sd])
    rms = float(np.sqrt(np.mean(r ** 2)))
    ax.set_title(f"{panel.label}: RMS {rms:.3g} {panel.unit}, {r.size} updates, {int(out.sum())} beyond 3 sigma",
                 fontsize=8, loc="right")
    ax.set_ylabel(panel.label, fontsize=8)
    ax.grid(alpha=0.3)


def _scale(ax, size: np.ndarray, band: np.ndarray) -> None:
    """A symmetric log axis, linear within the typical size (the median of ``size``, the absolute
    residuals, and of ``band``, the 3-sigma half-widths), when the largest value is more than
    :data:`LINEAR_SPAN` times that: the first updates of a filter that converges are orders of
    magnitude larger than the last, and would flatten them into a line."""
    values = np.concatenate([size, band])
    values = values[np.isfinite(values) & (values > 0)]
    if values.size == 0:
        return
    typical = float(np.median(values))
    if values.max() > LINEAR_SPAN * typical:
        from matplotlib.ticker import FuncFormatter

        ax.set_yscale("symlog", linthresh=typical)
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))  # plain text: no mathtext to lay out
        ax.text(0.99, 0.04, f"linear within +-{typical:.3g}, logarithmic beyond", transform=ax.transAxes,
                fontsize=6, ha="right", color="0.35")


def residual_figure(panels: list[ResidualPanel], title: str = "", epoch: str = "", sensor: str = "") -> Any:
    """The matplotlib Figure of ``panels`` (at least one), one axis each, top to bottom; ``epoch``
    (UTC text) names the time axis' zero, ``sensor`` the sensor's own site."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 1.6 + 1.9 * len(panels)))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for ax, panel in zip(axes, panels):
        _draw(ax, panel)
        ax.text(0.01, 0.96, _site_name(panel.site, sensor), transform=ax.transAxes, fontsize=7, va="top")
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:]:
        more = ax.get_legend_handles_labels()
        handles += [h for h, lb in zip(*more) if lb not in labels]
        labels += [lb for lb in more[1] if lb not in labels]
    axes[0].legend(handles, labels, fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.12), ncol=4,
                   frameon=False, borderaxespad=0.2)
    axes[-1].set_xlabel("days since " + (epoch or "the scenario epoch"))
    fig.suptitle((title + ": " if title else "") + "filter residuals against the predicted measurement", fontsize=10)
    fig.tight_layout()
    return fig


def write_residual_figure(directory: str | Path, measurements=None, title: str = "", epoch: str = "",
                          sensor: str = "") -> Path | None:
    """Draw the residuals of the run in ``directory`` (its ``steps.parquet``) into
    ``directory/residuals.svg`` and return that path; None, with any earlier figure removed, when
    the table holds no residual. ``measurements``, ``title``, ``epoch``, ``sensor``: see
    :func:`residual_panels` and :func:`residual_figure`."""
    import pyarrow.parquet as pq

    from cistrack.results.atomic_files import atomic_target

    d = Path(directory)
    panels = residual_panels(pq.read_table(d / "steps.parquet"), measurements)
    if not panels:
        (d / FIGURE).unlink(missing_ok=True)
        return None
    fig = residual_figure(panels, title, epoch, sensor)
    with atomic_target(d / FIGURE) as tmp:
        fig.savefig(tmp, format="svg")
    return d / FIGURE


def write_run_residual_figure(ctx, directory: Path, status: str) -> Path | None:
    """The residual figure of the run ``ctx`` (a :class:`~cistrack.runs.run_context.RunContext`)
    that has written its results into ``directory``, drawn when its steps were merged and it was
    not interrupted (an earlier run's figure is removed otherwise). A failure to write (a full disk)
    is a warning on the ``cistrack`` logger: the run's results stand without the figure."""
    d = Path(directory)
    if status == "interrupted" or not (d / "steps.parquet").is_file():
        (d / FIGURE).unlink(missing_ok=True)
        return None
    from cistrack import units

    try:
        return write_residual_figure(d, ctx.measurements, ctx.run_id, units.format_utc(ctx.epoch)[:19] + "Z",
                                     ctx.scenario.components["sensor"].name)
    except OSError as exc:
        logging.getLogger("cistrack").warning(f"{d / FIGURE}: the residual figure was not written ({exc})")
        return None
