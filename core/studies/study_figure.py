"""A compact figure of a study, for notebooks: what :meth:`cistrack.api.StudyResult.plot` draws.

One panel per metric (position error, 1-sigma position, NEES, entropy; those the runs have),
sharing the time axis (days since the epoch); per group of runs (a filter, IOD and scenario) the
median over its seeds and the 5-95 % band, each seed's series held between its steps
(:func:`cistrack.studies.report_plots.band_over_seeds`). NEES carries the chi-square 5-95 % band of
6 degrees of freedom and its median. A panel whose values span more than two decades is on a log axis. A group
whose runs mostly diverged or failed is drawn dashed, without a band, and does not set the
limits (a collapsed filter's NEES of 1e38 would flatten every other line). The files of
``cistrack study report`` (:mod:`cistrack.studies.report_plots`) are the full version.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.errors import CistrackError
from cistrack.studies.report_plots import CHI2_DOF, band_over_seeds, nees_band, nees_median
from cistrack.studies.run_figure import log_scale_fits

__all__ = ["STUDY_PANELS", "plot_study_groups"]

STUDY_PANELS: tuple[tuple[str, str], ...] = (
    ("pos_err_km", "position error (km)"),
    ("sigma_pos_km", "1-sigma position (km)"),
    ("nees", "NEES"),
    ("entropy", "entropy (nats)"),
)
_OFF_KINDS = ("diverged", "filter-failed")
_GRID = 400


def _series(steps: list[Any], column: str) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for df in steps:
        if column in df.columns and "t_days" in df.columns and len(df):
            d = df.sort_values("t_days", kind="stable")
            y = np.asarray(d[column].to_numpy(dtype=float, na_value=np.nan), dtype=float)
            if np.isfinite(y).any():
                out.append((np.asarray(d["t_days"].to_numpy(dtype=float), dtype=float), y))
    return out


def _mostly_off(summaries: list[dict[str, Any]]) -> bool:
    bad = sum(1 for s in summaries if (s.get("verdict") or {}).get("kind") in _OFF_KINDS or s.get("status") != "finished")
    return 2 * bad > len(summaries)


def plot_study_groups(groups: dict[str, dict[str, list[Any]]], title: str = "") -> Any:
    """The figure (a matplotlib Figure) of ``groups[label] = {"steps": [DataFrame per seed],
    "summaries": [summary dict per seed]}``.

    Raises CistrackError when no run has a step.
    """
    import matplotlib.pyplot as plt

    times = [s[0] for g in groups.values() for s in _series(g["steps"], "t_days")]
    if not times:
        raise CistrackError("no run of the study has steps to plot")
    grid = np.linspace(min(float(np.nanmin(t)) for t in times), max(float(np.nanmax(t)) for t in times), _GRID)
    panels = [p for p in STUDY_PANELS if any(_series(g["steps"], p[0]) for g in groups.values())]
    fig = plt.figure(figsize=(8.0, 1.2 + 2.0 * len(panels)))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (column, label) in zip(axes, panels):
        shown: list[np.ndarray] = []
        late: list[tuple[np.ndarray, dict[str, Any]]] = []
        for i, (name, g) in enumerate(sorted(groups.items())):
            series = _series(g["steps"], column)
            if not series:
                continue
            p5, p50, p95 = band_over_seeds(series, grid)
            n = f"{len(series)} seed{'s' if len(series) != 1 else ''}"
            if _mostly_off(g["summaries"]):
                late.append((p50, dict(color=f"C{i}", lw=1.0, ls="--", drawstyle="steps-post",
                                        label=f"{name}: mostly diverged, median of {n} (clipped)")))
                continue
            shown += [p5, p50, p95]
            ax.fill_between(grid, p5, p95, color=f"C{i}", alpha=0.15, lw=0, step="post")
            ax.plot(grid, p50, color=f"C{i}", lw=1.5, drawstyle="steps-post", label=f"{name}: median of {n}, 5-95 %")
        if column == "nees":
            lo, hi = nees_band(CHI2_DOF)
            ax.axhspan(lo, hi, color="0.5", alpha=0.2, lw=0, label=f"chi-square({CHI2_DOF}) 5-95 %")
            ax.axhline(nees_median(CHI2_DOF), color="0.4", lw=0.8, ls="--",
                       label=f"chi-square({CHI2_DOF}) median {nees_median(CHI2_DOF):.2f} (beside the medians)")
            shown.append(np.array([lo, hi]))
        values = np.concatenate([np.ravel(v) for v in shown]) if shown else np.zeros(0)
        if log_scale_fits(values):
            ax.set_yscale("log")
        finite = values[np.isfinite(values) & ((values > 0) if ax.get_yscale() == "log" else True)]
        if finite.size:
            lo_v, hi_v = float(finite.min()), float(finite.max())
            ax.set_ylim(*((lo_v / 2, hi_v * 2) if ax.get_yscale() == "log" else
                          (lo_v - 0.06 * (hi_v - lo_v + 1e-9), hi_v + 0.06 * (hi_v - lo_v + 1e-9))))
        for y, style in late:
            lo_a, hi_a = ax.get_ylim()
            ax.plot(grid, np.where((y >= lo_a) & (y <= hi_a), y, np.nan), **style)
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    axes[-1].set_xlabel("time since epoch (days)")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig
