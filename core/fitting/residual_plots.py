"""Post-fit residual plots, one per observing site: ``residuals-<site>.png`` and ``.svg``.

Each figure has one panel per fitted component (RA x cos(Dec) and Dec for RA/Dec), O - C in
arcsec (km for a range) against the time in days since the first observation of the arc (all
sites share the axis), the used observations as dots, the rejected ones as red crosses, and the
band of three times each observation's stated noise. The vertical axis is set by the used
observations and the band: a rejected observation beyond it (a gross outlier, thousands of arcsec
off) is drawn as a red triangle at the panel's edge with its value written beside it, so that it
does not flatten the used ones into a line. Drawn with matplotlib's object interface (no global
backend is changed).
"""
from __future__ import annotations

import re
from datetime import datetime
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.results.atomic_files import atomic_target
from cistrack.results.output_paths import distinct_stems

__all__ = ["plot_residuals", "residual_figure", "save_figure", "site_file_stem", "site_file_stems"]


def site_file_stem(site: str) -> str:
    """``residuals-<site>`` with the site key made safe for a file name ("" -> "residuals-sensor")."""
    s = re.sub(r"[^A-Za-z0-9_.-]+", "_", site).strip("._")
    return f"residuals-{s or 'sensor'}"


def site_file_stems(sites: list[str]) -> dict[str, str]:
    """:func:`site_file_stem` of each site; sites whose stems coincide (``a/b`` and ``a_b``) each get
    a short hash of the site key appended, so that no site's plot replaces another's."""
    return distinct_stems(sites, site_file_stem)


def plot_residuals(directory: str | Path, table, epoch: datetime, designation: str = "") -> list[Path]:
    """Write a PNG and an SVG per site of the :class:`~cistrack.least_squares.ResidualTable` ``table``
    (times TU since ``epoch``) into ``directory``; returns the files written."""
    d = Path(directory)
    if len(table) == 0:
        return []
    written: list[Path] = []
    try:
        for site, stem in site_file_stems(table.sites.tolist()).items():
            fig = residual_figure(table, site, epoch, designation)
            for suffix in (".png", ".svg"):
                written.append(save_figure(fig, d / f"{stem}{suffix}"))
    except OSError:
        for p in written:  # no plot of this table without the others
            p.unlink(missing_ok=True)
        raise
    return written


def save_figure(fig, path: str | Path) -> Path:
    """Save the matplotlib Figure ``fig`` (110 dpi, the format of ``path``'s suffix) whole or not at
    all: a temporary file and a rename. An OSError (a full disk) names ``path`` as its filename."""
    p = Path(path)
    try:
        with atomic_target(p) as tmp:
            fig.savefig(tmp, dpi=110, format=p.suffix.lstrip(".") or None)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(p)) from exc
    return p


def residual_figure(table, site: str, epoch: datetime, designation: str = ""):
    """The matplotlib Figure of one ``site``'s residuals in ``table`` (a non-empty
    :class:`~cistrack.least_squares.ResidualTable`, times TU since ``epoch``). The legend sits above the top
    panel, outside every panel, so that it hides no residual wherever the points fall."""
    from matplotlib.figure import Figure

    t0 = float(np.min(table.times))
    days = units.tu_to_days(np.asarray(table.times) - t0)
    sigma = np.where(table.normalised != 0, np.abs(table.o_c / np.where(table.normalised == 0, 1, table.normalised)), np.nan)
    labels = [c.replace("_arcsec", " (arcsec)").replace("_km", " (km)").replace("ra_cos_dec", "RA cos(Dec)")
              .replace("declination", "Dec").replace("_", " ") for c in table.column_names()]
    start = units.format_utc(units.tu_to_utc(epoch, t0))[:19] + "Z"
    rows = table.sites == site
    fig = Figure(figsize=(8.0, 2.4 + 2.0 * len(labels)))
    axes = fig.subplots(len(labels), 1, sharex=True, squeeze=False)[:, 0]
    used, rej = rows & ~table.rejected, rows & table.rejected
    for j, ax in enumerate(axes):
        band = 3.0 * sigma[rows, j]
        order = np.argsort(days[rows])
        ax.fill_between(days[rows][order], -band[order], band[order], color="0.85", step="mid",
                        label="3 sigma (stated noise)")
        ax.axhline(0.0, color="0.4", lw=0.8)
        ax.plot(days[used], table.o_c[used, j], "o", ms=3.5, color="tab:blue", label="used")
        if np.any(rej):
            _rejected(ax, days[rej], table.o_c[rej, j], np.concatenate([band, np.abs(table.o_c[used, j])]))
        rms = float(np.sqrt(np.mean(table.o_c[used, j] ** 2))) if np.any(used) else float("nan")
        ax.set_ylabel(f"O-C {labels[j]}")
        ax.set_title(f"RMS {rms:.3g} (used)", fontsize=8, loc="right")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=3, frameon=False,
                   borderaxespad=0.2)
    axes[-1].set_xlabel(f"days since {start} (first observation of the arc)")
    n_rej = int(np.sum(rej))
    fig.suptitle(f"{designation + ': ' if designation else ''}post-fit residuals, site {site or '(sensor)'}: "
                 f"{int(np.sum(rows))} observations, {n_rej} rejected", fontsize=10)
    fig.tight_layout()
    return fig


def _rejected(ax, days: np.ndarray, o_c: np.ndarray, kept: np.ndarray) -> None:
    """Rejected residuals ``o_c`` at ``days`` on ``ax``: crosses within the axis that the used ones
    and the band (``kept``, absolute values) set; beyond it, triangles at the edge with the value."""
    lim = 1.15 * float(np.nanmax(kept)) if kept.size and np.isfinite(np.nanmax(kept)) and np.nanmax(kept) > 0 else None
    inside = np.ones(o_c.shape, dtype=bool) if lim is None else np.abs(o_c) <= lim
    ax.plot(days[inside], o_c[inside], "x", ms=6, color="tab:red", label="rejected")
    if lim is None or np.all(inside):
        return
    ax.set_ylim(-1.08 * lim, 1.08 * lim)
    for d, v in zip(days[~inside], o_c[~inside]):
        edge = np.sign(v) * lim
        ax.plot([d], [edge], "^" if v > 0 else "v", ms=7, color="tab:red")
        ax.annotate(f"{v:,.0f}", (d, edge), textcoords="offset points", xytext=(5, -9 if v > 0 else 3),
                    fontsize=7, color="tab:red")
