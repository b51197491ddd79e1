"""The figure of one run: what :meth:`cistrack.api.Run.plot` draws.

Panels sharing the time axis (days since the epoch), each drawn only where the run has its
column: position error (km) under the 3-sigma envelope of the 1-sigma position, the 1-sigma
position (root-sum-square of the per-axis sigmas, km) in the band from the smallest to the largest
per-axis sigma, NEES with the chi-square 5-95 % band of a consistent filter (6 degrees of freedom)
and its median, NIS with its chi-square band (only for a run without a truth, which has no
error and no NEES: the NIS is its consistency), and differential entropy (nats). A panel whose values span more than
two decades is on a log axis. Ticks at the bottom mark the updates, a triangle at the top and a
dotted line the time custody was lost. A quantity that is undefined (NaN) after some step, a
filter whose belief became NaN, stops there, with a note on its panel saying after which step.
"""
from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from cistrack.errors import CistrackError
from cistrack.studies.report_plots import CHI2_DOF, nees_band, nees_median

__all__ = ["plot_run", "RUN_PANELS", "log_scale_fits", "undefined_after"]

#: (column, axis label) of each panel, top to bottom; a panel is drawn when its column has values.
RUN_PANELS: tuple[tuple[str, str], ...] = (
    ("pos_err_km", "position error (km)"),
    ("sigma_pos_km", "1-sigma position (km)"),
    ("nees", "NEES"),
    ("nis", "NIS"),
    ("entropy", "entropy (nats)"),
)
_SIGMA_AXES = ("sigma_x_km", "sigma_y_km", "sigma_z_km")


def _values(steps: Any, column: str) -> np.ndarray | None:
    """A column as floats (NaN for missing values), or None when the table lacks it or it has no finite value."""
    if column not in steps.columns:
        return None
    v = np.asarray(steps[column].to_numpy(dtype=float, na_value=np.nan), dtype=float)
    return v if np.isfinite(v).any() else None


def log_scale_fits(values: np.ndarray, decades: float = 2.0) -> bool:
    """Whether ``values`` are all positive (where finite) and span more than ``decades`` decades."""
    v = values[np.isfinite(values)]
    if v.size == 0 or (v <= 0).any():
        return False
    return bool(np.log10(v.max() / v.min()) > decades)


def _chi2_band(ax: Any, dof: int, what: str, y: np.ndarray) -> None:
    """The chi-square 5-95 % band and median line of ``dof`` degrees of freedom; a log axis when
    the values and the band together span more than two decades."""
    lo, hi = nees_band(dof)
    ax.axhspan(lo, hi, color="0.5", alpha=0.2, lw=0, label=f"{what} of a consistent filter: chi-square({dof}) 5-95 %")
    ax.axhline(nees_median(dof), color="0.4", lw=0.8, ls="--", label=f"chi-square({dof}) median {nees_median(dof):.2f}")
    if log_scale_fits(np.append(y, [lo, hi])):
        ax.set_yscale("log")


def plot_run(steps: Any, summary: dict[str, Any], title: str = "") -> Any:
    """The figure (a matplotlib Figure) of one run from its per-step table ``steps`` (a pandas
    DataFrame with the columns of ``steps.parquet``) and its summary (``RunSummary.to_dict()``).

    Raises CistrackError when the table has no time column or no step.
    """
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    if "t_days" not in steps.columns:
        raise CistrackError("the steps to plot are not a steps table (no column t_days)")
    if len(steps) == 0:
        raise CistrackError("the run has no steps to plot (it ended before its first step was written)")
    steps = steps.sort_values("t_days", kind="stable")
    t = np.asarray(steps["t_days"].to_numpy(dtype=float), dtype=float)
    panels = [(c, label) for c, label in RUN_PANELS if _values(steps, c) is not None]
    if any(c == "nees" for c, _ in panels):  # with a truth the NEES says it: no NIS panel
        panels = [(c, label) for c, label in panels if c != "nis"]
    fig: Figure = plt.figure(figsize=(8.0, 1.2 + 2.0 * len(panels)))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    sigma = _values(steps, "sigma_pos_km")
    for ax, (column, label) in zip(axes, panels):
        y = _values(steps, column)
        assert y is not None
        ax.plot(t, y, color="C0", lw=1.4, marker=".", ms=4, label=label.split(" (")[0])
        if column == "pos_err_km" and sigma is not None:
            ax.fill_between(t, 0.0, 3.0 * sigma, color="C1", alpha=0.18, lw=0, label="3-sigma envelope (3 x RSS sigma)")
        if column == "sigma_pos_km":
            _sigma_band(ax, steps, t)
        if column == "nees":
            _chi2_band(ax, CHI2_DOF, "NEES", y)
        if column == "nis":
            dof = _values(steps, "nis_dof")
            m = int(np.nanmedian(dof)) if dof is not None else 2
            _chi2_band(ax, max(m, 1), "NIS", y)
        if column not in ("nees", "nis") and log_scale_fits(y):
            ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.3)
        _note_undefined(ax, steps, column, y)
    _mark_updates_and_custody(axes, steps, t, summary)
    axes[-1].set_xlabel("time since epoch (days)")
    for ax in axes:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    verdict = (summary.get("verdict") or {}).get("kind", "")
    fig.suptitle(title + (f": {verdict}" if verdict else ""), fontsize=11)
    fig.tight_layout()
    return fig


def _sigma_band(ax: Any, steps: Any, t: np.ndarray) -> None:
    """The band from the smallest to the largest per-axis sigma (a gap where they are undefined)."""
    per_axis = [v for v in (_values(steps, c) for c in _SIGMA_AXES) if v is not None]
    if not per_axis:
        return
    stack = np.vstack(per_axis)
    with warnings.catch_warnings():  # a step where every sigma is NaN is a gap, said by _note_undefined
        warnings.simplefilter("ignore", RuntimeWarning)
        lo, hi = np.nanmin(stack, axis=0), np.nanmax(stack, axis=0)
    ax.fill_between(t, lo, hi, color="C0", alpha=0.18, lw=0, label="band: smallest to largest per-axis sigma")


def undefined_after(steps: Any, column: str, y: np.ndarray) -> int | None:
    """The step after which ``column`` (values ``y``, in the order of ``steps``) is undefined (NaN or
    infinite) on every row of a kind where it is ever defined (a NIS only at updates), or None when
    it is defined to the end."""
    kinds = steps["kind"].to_numpy() if "kind" in steps.columns else np.full(len(y), "")
    finite = np.isfinite(y)
    rows = np.isin(kinds, np.unique(kinds[finite]))
    last = int(np.flatnonzero(finite)[-1])
    if not (rows[last + 1:] & ~finite[last + 1:]).any():
        return None
    index = steps["step"].to_numpy() if "step" in steps.columns else np.arange(len(y))
    return int(index[last])


def _note_undefined(ax: Any, steps: Any, column: str, y: np.ndarray) -> None:
    """A note on the panel when its quantity is undefined (NaN) after some step: the line just stops."""
    k = undefined_after(steps, column, y)
    if k is not None:
        ax.text(0.99, 0.95, f"undefined (NaN) after step {k}", transform=ax.transAxes, ha="right", va="top",
                fontsize=8, color="C3")


def _mark_updates_and_custody(axes: Any, steps: Any, t: np.ndarray, summary: dict[str, Any]) -> None:
    """Ticks at the updates' times on every panel, and the custody loss (if any) as a dotted line
    with a triangle at the top."""
    kinds = steps["kind"].to_numpy() if "kind" in steps.columns else np.array([])
    days = t[kinds == "update"] if kinds.size else np.zeros(0)
    lost = None if summary.get("custody_kept", True) else summary.get("custody_lost_t_days")
    for i, ax in enumerate(axes):
        ax.plot(days, np.full_like(days, 0.03), marker="|", ls="none", color="0.2", ms=8,
                transform=ax.get_xaxis_transform(), clip_on=False, label="updates" if i == 0 else None)
        if lost is not None:
            ax.axvline(lost, color="C3", lw=1.0, ls=":")
            ax.plot([lost], [1.0], marker="v", ls="none", color="C3", ms=8, transform=ax.get_xaxis_transform(),
                    clip_on=False, label=f"custody lost (day {lost:.3g})" if i == 0 else None)
