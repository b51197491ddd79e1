"""Study report figures: per filter the median and 5-95 % band across seeds over time.

One figure per (scenario, IOD) compares the filters of a study on four panels sharing the time
axis (days since the epoch): position error (km, log), 1-sigma position (root-sum-square of the
per-axis sigmas, km, log), NEES with the chi-square 5-95 % band of a consistent filter (6
degrees of freedom) and its median as the reference line, and differential entropy (nats). Each
seed's series is held constant between its steps and sampled on a common grid; the line is the
median over seeds, the band the 5th to 95th percentile. Ticks at the bottom mark the measurement
times of the first seed, triangles at the top the custody losses (the times the custody rule
fired; a row per filter, one triangle per time with the number of runs beside it when several),
and a dotted black line the information bound's RMS position sigma
(:mod:`cistrack.evaluation.information_bound`) in the error and sigma panels. Written as PNG, SVG
and PDF.

A study whose runs have truth burns or detections also gets two maneuver figures
(:func:`plot_maneuver_detection`, :func:`plot_false_alarms`) from the rows of
:func:`cistrack.studies.maneuver_scores.maneuver_rows`.

A gap without measurements longer than 10 days and a fifth of the span (Example 3's 150-day
shutoff) is shrunk to a hatched band that names its length (:mod:`cistrack.studies.time_axis`),
so the passes on both sides stay legible.

A filter that diverged or failed in most of its runs never sets the axes: the limits come from the
other filters, and it is drawn as a thin dashed median (no band), clipped at the edge, its legend
entry saying so.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cistrack.studies.time_axis import GapAxis

from cistrack.results.atomic_files import atomic_target

__all__ = ["PANELS", "CHI2_DOF", "LOSS_ROW_STEP", "band_over_seeds", "loss_marks", "nees_band", "nees_median",
           "plot_study", "save_figure",
           "FORMATS", "plot_maneuver_detection", "plot_false_alarms", "detection_lines"]

CHI2_DOF = 6
FORMATS = ("png", "svg", "pdf")
PANELS: tuple[tuple[str, str, str], ...] = (
    ("pos_err_km", "position error (km)", "log"),
    ("sigma_pos_km", "1-sigma position\n(RSS of axes, km)", "log"),
    ("nees", "NEES", "log"),
    ("entropy", "entropy (nats)", "linear"),
)
_GRID = 600
_OFF_SCALE_KINDS = ("diverged", "filter-failed", "failed")
"""Verdict kinds of a run that does not set a figure's axes."""


def _column(table: Any, name: str) -> np.ndarray | None:
    if name not in table.column_names:
        return None
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=float)


def _held(t: np.ndarray, y: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """y (K,) at times t (K,, non-decreasing) held until the next step, sampled at grid (G,);
    NaN before the first step and after the last."""
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok]
    out = np.full(grid.shape, np.nan)
    if t.size == 0:
        return out
    idx = np.searchsorted(t, grid, side="right") - 1
    inside = (idx >= 0) & (grid <= t[-1] + 1e-12)
    out[inside] = y[idx[inside]]
    return out


def band_over_seeds(series: list[tuple[np.ndarray, np.ndarray]], grid: np.ndarray,
                    q: tuple[float, float, float] = (5.0, 50.0, 95.0)) -> np.ndarray:
    """Percentiles (3, G) over seeds of step series [(t (K,), y (K,)), ...] held on ``grid`` (G,);
    NaN where no seed has a value."""
    held = np.stack([_held(t, y, grid) for t, y in series])
    out = np.full((len(q), grid.size), np.nan)
    have = np.isfinite(held).any(axis=0)
    if have.any():
        out[:, have] = np.nanpercentile(held[:, have], q, axis=0)
    return out


def _nees_locator(lo: float, hi: float):
    """Ticks 1-2-5 per decade over a few decades; over many (a diverged run's NEES reaches 1e10)
    that asks matplotlib for too many ticks and it draws none, so then whole decades."""
    import matplotlib.ticker
    decades = np.log10(max(hi, 1e-300) / max(lo, 1e-300))
    if decades <= 5.0:
        return matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0))
    return matplotlib.ticker.LogLocator(subs=(1.0,), numticks=8)


def nees_band(dof: int = CHI2_DOF, level: float = 0.90) -> tuple[float, float]:
    """The central ``level`` interval of a chi-square variable with ``dof`` degrees of freedom."""
    from scipy.stats import chi2

    a = 0.5 * (1.0 - level)
    return float(chi2.ppf(a, dof)), float(chi2.ppf(1.0 - a, dof))


def nees_median(dof: int = CHI2_DOF) -> float:
    """The median of a chi-square variable with ``dof`` degrees of freedom (5.35 for 6): the
    reference for the plotted medians of NEES."""
    from scipy.stats import chi2

    return float(chi2.ppf(0.5, dof))


def _series(tables: list, key: str) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for t in tables:
        x, y = _column(t, "t_days"), _column(t, key)
        if x is not None and y is not None:
            order = np.argsort(x, kind="stable")
            out.append((x[order], y[order]))
    return out


def _measurement_days(table: Any) -> np.ndarray:
    kind = table.column("kind").to_pylist() if "kind" in table.column_names else []
    t = _column(table, "t_days")
    if t is None:
        return np.zeros(0)
    return np.array([ti for ti, k in zip(t, kind) if k == "update"])


def save_figure(fig: Any, stem: Path) -> list[Path]:
    """Write ``fig`` as ``stem``.png/.svg/.pdf (text stays text in SVG and PDF: editable,
    searchable, TrueType fonts as journals ask), close it and return the paths written. The
    extension is appended: a stem with a dot (a swept label, ``example-1-burn[dv=0.3]__noisy-range``)
    keeps its whole name."""
    import matplotlib
    import matplotlib.pyplot as plt

    files = []
    with matplotlib.rc_context({"svg.fonttype": "none", "pdf.fonttype": 42}):
        for ext in FORMATS:
            f = stem.with_name(f"{stem.name}.{ext}")
            with atomic_target(f) as tmp:  # never a partial figure (a full disk)
                fig.savefig(tmp, dpi=130, format=ext)
            files.append(f)
    plt.close(fig)
    return files


def _off_scale(summaries: list[dict[str, Any]]) -> tuple[bool, int]:
    """Whether a filter's runs mostly diverged or failed (then it does not set the axes), and how many did."""
    bad = sum(1 for x in summaries
              if ((x.get("verdict") or {}).get("kind") in _OFF_SCALE_KINDS or x.get("status") not in (None, "finished")))
    return bool(summaries) and 2 * bad > len(summaries), bad


def _limits(values: list[np.ndarray], scale: str, extra: tuple[float, ...] = ()) -> tuple[float, float] | None:
    """Axis limits holding every finite value (positive ones on a log axis), with a margin."""
    v = np.concatenate([np.ravel(x) for x in values] + [np.asarray(extra, dtype=float)]) if values or extra else np.zeros(0)
    v = v[np.isfinite(v)]
    if scale == "log":
        v = v[v > 0]
    if v.size == 0:
        return None
    lo, hi = float(v.min()), float(v.max())
    if scale == "log":
        return lo / 2.0, hi * 2.0
    pad = 0.06 * (hi - lo) if hi > lo else max(1.0, abs(hi) * 0.1)
    return lo - pad, hi + pad


def _wrapped_title(text: str, width: int = 78) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text


@dataclass
class _Figure:
    """One figure being drawn: a (scenario, IOD) case's panels on the shared time axis."""

    fig: Any
    axes: list
    panels: list[tuple[str, str, str]]
    tax: GapAxis
    grid: np.ndarray
    """Common sampling times (days, (G,)); ``xg`` the same on the drawn (gap-shrunk) axis."""
    xg: np.ndarray
    shown: dict[str, list[np.ndarray]] = field(default_factory=dict)
    """Per panel key, the values that set its axis."""
    late: list[tuple[Any, str, np.ndarray, dict[str, Any]]] = field(default_factory=list)
    """Off-scale medians, drawn once the axes are set."""

    @property
    def keys(self) -> list[str]:
        return [k for k, _, _ in self.panels]

    @property
    def nees_ax(self) -> Any:
        """The NEES panel, or None (no truth: no NEES, nor error)."""
        return self.axes[self.keys.index("nees")] if "nees" in self.keys else None


def _time_grid(filters: dict[str, dict[str, Any]]) -> tuple[GapAxis, np.ndarray, np.ndarray] | None:
    """The case's time axis (long gaps shrunk: the passes around them stay legible), its sampling
    grid (days) and the grid on the drawn axis; None when no table has times."""
    all_t = [x for g in filters.values() for t in g["tables"] for x in [_column(t, "t_days")] if x is not None and x.size]
    if not all_t:
        return None
    t_lo, t_hi = min(float(np.nanmin(x)) for x in all_t), max(float(np.nanmax(x)) for x in all_t)
    days_all = np.unique(np.concatenate([_measurement_days(t) for g in filters.values() for t in g["tables"][:1]]
                                        or [np.zeros(0)]))
    tax = GapAxis.from_times(days_all, t_lo, t_hi)
    grid = tax.inverse(np.linspace(float(tax.forward(t_lo)), float(tax.forward(t_hi)), _GRID))
    return tax, grid, tax.forward(grid)


def _draw_bands(f: _Figure, ci: int, flt: str, g: dict[str, Any], thin: bool) -> None:
    """A filter's median and 5-95 % band on each panel (an off-scale filter: its median, later)."""
    color = f"C{ci}"
    off, n_bad = _off_scale(g["summaries"])
    for ax, (key, _, _) in zip(f.axes, f.panels):
        series = _series(g["tables"], key)
        if not series:
            continue
        p5, p50, p95 = band_over_seeds(series, f.grid)
        if off:  # drawn once the axes are set, clipped, never setting them
            f.late.append((ax, key, p50, dict(color=color, lw=1.0, ls="--", drawstyle="steps-post",
                                              label=f"{flt}: diverged {n_bad} of {len(g['summaries'])} "
                                                    "runs, median (clipped)")))
            continue
        f.shown[key] += [p5, p50, p95]
        ax.fill_between(f.xg, p5, p95, color=color, alpha=0.10 if thin else 0.18, lw=0, step="post")
        ax.plot(f.xg, p50, color=color, lw=1.6, drawstyle="steps-post",
                label=f"{flt}: median of {len(series)} seed{'s' if len(series) != 1 else ''}, band 5-95 %")


LOSS_ROW_STEP = 0.045
"""Axes fraction between the rows of custody-loss triangles of successive filters (the first at the
top edge), so that filters losing custody at the same time do not hide one another."""


def loss_marks(lost_days: list[float], resolution_days: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """The distinct custody-loss times (days, to ``resolution_days``) and how many runs lost custody
    at each: one triangle per time, labelled with its count, instead of one per run on top of one
    another."""
    if not lost_days:
        return np.zeros(0), np.zeros(0, dtype=int)
    keys, counts = np.unique(np.round(np.asarray(lost_days, dtype=float) / resolution_days), return_counts=True)
    return keys * resolution_days, counts


def _draw_marks(f: _Figure, ci: int, flt: str, g: dict[str, Any]) -> None:
    """Triangles at the top at each custody loss (a row per filter, a count beside a triangle that
    stands for several runs); for the first filter, ticks at the bottom at the measurement times of
    its first seed."""
    color = f"C{ci}"
    lost = [s.get("custody_lost_t_days") for s in g["summaries"] if not s.get("custody_kept", True)]
    lost = [x for x in lost if x is not None]
    times, counts = loss_marks(lost)
    y = 1.0 - LOSS_ROW_STEP * ci
    for ax in f.axes:
        if lost:
            x = f.tax.forward(times)
            ax.plot(x, [y] * len(x), marker="v", ls="none", color=color, ms=7,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label=f"{flt}: custody lost ({len(lost)} of {len(g['summaries'])} runs)")
            for xi, n in zip(x, counts):
                if n > 1:
                    ax.text(xi, y, f" {n}", transform=ax.get_xaxis_transform(), color=color, fontsize=7,
                            ha="left", va="center", clip_on=False)
    first = g["tables"][0] if g["tables"] else None
    if first is not None and ci == 0:
        days = _measurement_days(first)
        for ax in f.axes:
            ax.plot(f.tax.forward(days), np.full_like(days, 0.03), marker="|", ls="none", color="0.2", ms=10, mew=1.5,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="measurement times (first seed)" if ax is f.axes[0] else None)


def _draw_references(f: _Figure, filters: dict[str, dict[str, Any]], chi: tuple[float, float]) -> None:
    """The information bound in the error and sigma panels, the chi-square band and median in NEES."""
    keys = f.keys
    bound = [sr for g in filters.values() for sr in [_series(g["tables"], "bound_pos_km")] if sr]
    if bound:  # the information bound along the truth: the same for every filter from one IOD
        b50 = band_over_seeds(bound[0], f.grid)[1]
        for key in ("pos_err_km", "sigma_pos_km"):
            if key in keys:
                f.axes[keys.index(key)].plot(f.xg, b50, color="k", lw=1.2, ls=":", drawstyle="steps-post",
                                             label="information bound (posterior CRB along the truth), median")
                f.shown[key].append(b50)
    nees_ax = f.nees_ax
    if nees_ax is not None:
        nees_ax.axhspan(*chi, color="0.5", alpha=0.15, lw=0, label=f"consistent filter: chi-square({CHI2_DOF}) 5-95 %")
        nees_ax.axhline(nees_median(), color="0.4", lw=0.8, ls="--",
                        label=f"chi-square({CHI2_DOF}) median {nees_median():.2f} (beside the plotted medians)")


def _set_y_axes(f: _Figure, filters: dict[str, dict[str, Any]], chi: tuple[float, float]) -> None:
    """Each panel's label, scale, limits and ticks, set by the filters on scale; then the off-scale
    medians, clipped to the limits."""
    import matplotlib.ticker

    if all(_off_scale(g["summaries"])[0] for g in filters.values()):  # every filter diverged: they set the axes
        for g in filters.values():  # after all (beside any reference line, such as the information bound)
            for key, _, _ in f.panels:
                f.shown[key] += [band_over_seeds(sr, f.grid)[1] for sr in [_series(g["tables"], key)] if sr]
    nees_ax = f.nees_ax
    for ax, (key, label, scale) in zip(f.axes, f.panels):
        ax.set_ylabel(label)
        ax.set_yscale(scale)
        lim = _limits(f.shown[key], scale, chi if ax is nees_ax else ())
        if lim is not None:
            ax.set_ylim(*lim)
        if ax is nees_ax:  # plain numbers (6, 20), not 2 x 10^1
            ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.yaxis.set_major_locator(_nees_locator(*ax.get_ylim()))
        elif scale == "linear":
            ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=6))
        ax.grid(True, which="major", alpha=0.3)
    for ax, key, y, style in f.late:  # off-scale medians: only where inside the axes (no jumps across)
        lo, hi = ax.get_ylim()
        ax.plot(f.xg, np.where((y >= lo) & (y <= hi), y, np.nan), **style)


def _set_time_axis(f: _Figure) -> None:
    """The time label; shrunk gaps drawn hatched, their length named, ticks in days."""
    import matplotlib.ticker

    tax, axes = f.tax, f.axes
    axes[-1].set_xlabel("time since epoch (days)" + ("; gaps without measurements shrunk" if tax.shrinks else ""))
    if not tax.shrinks:
        return
    axes[-1].xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=10))
    axes[-1].xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(
        lambda v, _: f"{float(tax.inverse(np.asarray(v))):.4g}"))
    for a, b in tax.gaps:
        xa, xb = float(tax.forward(a)), float(tax.forward(b))
        for ax in axes:
            ax.axvspan(xa, xb, facecolor="none", edgecolor="0.55", hatch="//", lw=0)
        axes[0].text(0.5 * (xa + xb), 0.5, f"{b - a:.0f} d\nwithout\nmeasurements", ha="center",
                     va="center", fontsize=7, color="0.3", transform=axes[0].get_xaxis_transform())


def _legend_and_title(f: _Figure, title: str) -> None:
    """One legend below the panels (each label once) and the wrapped title."""
    handles, labels = [], []
    for ax in f.axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    f.fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8, frameon=False)
    f.fig.suptitle(_wrapped_title(title), fontsize=11)
    f.fig.tight_layout(rect=(0, 0.015 + 0.016 * ((len(labels) + 1) // 2), 1, 0.98))


def _plot_case(sc: str, iod: str, filters: dict[str, dict[str, Any]], rep_dir: Path, study_name: str,
               chi: tuple[float, float]) -> list[Path]:
    """The figure of one scenario and IOD variant, its filters side by side; the files written
    (none when no table has anything to draw)."""
    import matplotlib.pyplot as plt

    axis = _time_grid(filters)
    if axis is None:
        return []
    panels = [p for p in PANELS if any(_series(g["tables"], p[0]) for g in filters.values())]
    if not panels:
        return []
    fig, axes = plt.subplots(len(panels), 1, figsize=(8.5, 2.0 + 2.125 * len(panels)), sharex=True, squeeze=False)
    f = _Figure(fig, list(axes[:, 0]), panels, *axis, shown={key: [] for key, _, _ in panels})
    thin = len(filters) > 3  # several filters: lighter bands, so they stay legible
    for ci, (flt, g) in enumerate(sorted(filters.items())):
        _draw_bands(f, ci, flt, g, thin)
        _draw_marks(f, ci, flt, g)
    _draw_references(f, filters, chi)
    _set_y_axes(f, filters, chi)
    _set_time_axis(f)
    names = " vs ".join(sorted(filters))
    _legend_and_title(f, f"{names} on {sc}, IOD {iod}" + (f" (study {study_name})" if study_name else ""))
    return save_figure(fig, rep_dir / f"{sc}__{iod}")


def plot_study(groups: dict[tuple[str, str, str], dict[str, Any]], rep_dir: Path,
               study_name: str = "") -> list[Path]:
    """Write the figures; ``groups[(scenario, iod, filter)]`` holds ``tables`` (per-seed step
    tables) and ``summaries`` (per-seed run summaries). Returns the files written."""
    import matplotlib

    matplotlib.use("Agg")

    by_case: dict[tuple[str, str], dict[str, dict[str, Any]]] = {}
    for (sc, iod, flt), g in groups.items():
        by_case.setdefault((sc, iod), {})[flt] = g
    chi = nees_band()
    files: list[Path] = []
    for (sc, iod), filters in sorted(by_case.items()):
        files.extend(_plot_case(sc, iod, filters, rep_dir, study_name, chi))
    return files


_DV_SETTING = "truth.maneuvers.delta_v_ms"
_RESPONSE_SETTING = "maneuvers.response"
_LINESTYLES = ("-", "--", ":", "-.")
_MARKERS = ("o", "s", "^", "D", "v", "P")


def detection_lines(rows: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    """The detection curve's lines: label -> the rows on it (groups with burns and a burn size), in
    delta-v order. A line is a filter and response (and the other swept settings; the IOD and the
    scenario when the rows have several)."""
    pts = [r for r in rows if r.get("burns") and r.get("delta_v_ms")]
    iods, bases = {r["iod"] for r in pts}, {r.get("_base", r["scenario"]) for r in pts}
    lines: dict[str, list[dict[str, Any]]] = {}
    for r in pts:
        other = [f"{k.rsplit('.', 1)[-1]}={v:g}" if isinstance(v, float) else f"{k.rsplit('.', 1)[-1]}={v}"
                 for k, v in (r.get("_sweep") or {}).items() if k not in (_DV_SETTING, _RESPONSE_SETTING)]
        parts = [r["filter"], f"response {r.get('response') or '?'}", *other,
                 *([r["iod"]] if len(iods) > 1 else []), *([r.get("_base", r["scenario"])] if len(bases) > 1 else [])]
        lines.setdefault(", ".join(parts), []).append(r)
    return {k: sorted(v, key=lambda r: r["delta_v_ms"]) for k, v in sorted(lines.items())}


def _line_style(label: str, rows: list[dict[str, Any]], styles: dict[str, dict]) -> dict[str, Any]:
    """Colour by filter (by line with one filter), line style by response, marker by the rest of
    the line's label."""
    r = rows[0]
    filters, responses, rest = styles["filters"], styles["responses"], styles["rest"]
    other = label.split(", ", 2)[2:] or [""]
    colour = filters.index(r["filter"]) if len(filters) > 1 else styles["labels"].index(label)
    return {"color": f"C{colour % 10}",
            "ls": _LINESTYLES[responses.index(r.get("response")) % len(_LINESTYLES)],
            "marker": _MARKERS[rest.index(other[0]) % len(_MARKERS)]}


def _burns_per_point(pts: list[dict[str, Any]]) -> str:
    n = sorted({int(r["burns"]) for r in pts})
    return (f"{n[0]}" if len(n) == 1 else f"{n[0]}-{n[-1]}") + (" burn" if n == [1] else " burns") + " per point"


def _draw_detection(axes: list, lines: dict[str, list[dict[str, Any]]]) -> None:
    """P(detect) and P(within the next pass) with their Wilson intervals, each line dodged a little
    along the log axis so that the intervals stay apart."""
    every = [r for v in lines.values() for r in v]
    styles = {"filters": sorted({r["filter"] for r in every}),
              "responses": sorted({r.get("response") for r in every}, key=str),
              "rest": sorted({(k.split(", ", 2)[2:] or [""])[0] for k in lines}), "labels": list(lines)}
    n = len(lines)
    for j, (label, pts) in enumerate(lines.items()):
        dodge = 10 ** (0.025 * (j - (n - 1) / 2))
        x = np.array([r["delta_v_ms"] for r in pts]) * dodge
        style = _line_style(label, pts, styles)
        for ax, key in zip(axes, ("p_detect", "p_next_pass")):
            p = np.array([r[key] for r in pts], dtype=float)
            err = np.clip([p - np.array([r[f"{key}_lo"] for r in pts], dtype=float),
                           np.array([r[f"{key}_hi"] for r in pts], dtype=float) - p], 0.0, None)  # no -1e-17
            ax.errorbar(x, p, yerr=err, capsize=3, lw=1.4, ms=5, label=f"{label} ({_burns_per_point(pts)})"
                        if ax is axes[0] else None, **style)


def plot_maneuver_detection(rows: list[dict[str, Any]], rep_dir: Path, study_name: str = "") -> list[Path]:
    """``maneuver_detection``: P(detect) and P(detect within the next pass) against the burn's
    delta-v (log axis, ticks at the swept values), one line per filter and response, with 95 %
    Wilson intervals. No figure (``[]``) when no group has burns of one known size."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    lines = detection_lines(rows)
    if not lines:
        return []
    legend_in = 0.35 + 0.19 * ((len(lines) + 1) // 2)  # the legend's height below the panels (inches)
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2 + legend_in), sharey=True)
    _draw_detection(list(axes), lines)
    dvs = sorted({r["delta_v_ms"] for v in lines.values() for r in v})
    for ax, title in zip(axes, ("P(detect): an episode after the burn", "P(detect within the next pass)")):
        ax.set_xscale("log")
        ax.set_xticks(dvs)
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.set_xlim(dvs[0] / 1.6, dvs[-1] * 1.6)
        ax.set_ylim(-0.03, 1.03)
        ax.set_xlabel("burn delta-v (m/s)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("share of burns (Wilson 95 %)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(_wrapped_title("Maneuver detection against delta-v" + (f" (study {study_name})" if study_name else ""),
                                100), fontsize=11)
    fig.tight_layout(rect=(0, legend_in / (4.2 + legend_in), 1, 0.97))
    return save_figure(fig, rep_dir / "maneuver_detection")


def plot_false_alarms(rows: list[dict[str, Any]], rep_dir: Path, study_name: str = "") -> list[Path]:
    """``maneuver_false_alarms``: per group the share of runs with a false alarm (an episode matched
    to no truth burn), with its 95 % Wilson interval, as horizontal bars coloured by filter."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in rows if r.get("runs") and r.get("false_alarm_rate") is not None]
    if not rows:
        return []
    several_iods = len({r["iod"] for r in rows}) > 1
    filters = sorted({r["filter"] for r in rows})
    fig, ax = plt.subplots(figsize=(9.0, max(2.6, 1.2 + 0.26 * len(rows))))
    y = np.arange(len(rows))[::-1]
    rate = np.array([r["false_alarm_rate"] for r in rows], dtype=float)
    err = np.clip([rate - np.array([r["false_alarm_lo"] for r in rows], dtype=float),
                   np.array([r["false_alarm_hi"] for r in rows], dtype=float) - rate], 0.0, None)
    ax.barh(y, rate, xerr=err, capsize=2, color=[f"C{filters.index(r['filter']) % 10}" for r in rows], alpha=0.8,
            error_kw={"lw": 1.0})
    for yi, r in zip(y, rows):
        ax.text(1.02, yi, f"{r['false_alarm_runs']}/{r['runs']}", va="center", fontsize=7)
    ax.set_yticks(y)
    ax.set_yticklabels([f"{r['filter']} · {r['scenario']}" + (f" ({r['iod']})" if several_iods else "") for r in rows],
                       fontsize=7)
    ax.set_xlim(0, 1.12)
    ax.set_xlabel("runs with a false alarm / runs (Wilson 95 %)")
    ax.grid(True, axis="x", alpha=0.3)
    ax.set_title(_wrapped_title("False alarms: runs with an episode matched to no truth burn"
                                + (f" (study {study_name})" if study_name else ""), 90), fontsize=10)
    fig.tight_layout()
    return save_figure(fig, rep_dir / "maneuver_false_alarms")
