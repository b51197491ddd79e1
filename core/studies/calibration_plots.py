"""Study report figure of calibration: the histogram of the truth's final HDR level.

For a consistent belief the probability mass of the highest-density region whose boundary passes
through the truth is uniform on [0, 1] across runs: a pile-up near 1 means an overconfident
filter (truth in the tails), near 0 an underconfident one. One figure per (scenario, IOD) overlays
the filters' histograms (10 bins over [0, 1], counts of runs) with the count a uniform level would
give, as side-by-side bars (whole counts on the axis); the legend states each filter's Kolmogorov-Smirnov statistic and p-value against uniform
(:func:`cistrack.studies.calibration.uniformity_ks`). Written as ``<scenario>__<iod>__hdr`` PNG, SVG, PDF.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["plot_hdr_histograms", "HDR_BINS"]

HDR_BINS = 10


def _levels(summaries: list[dict[str, Any]]) -> np.ndarray:
    v = np.asarray([(s.get("final") or {}).get("hdr_level", np.nan) for s in summaries], dtype=float)
    return v[np.isfinite(v)]


def plot_hdr_histograms(groups: dict[tuple[str, str, str], list[dict[str, Any]]], rep_dir: Path,
                        rows: dict[tuple[str, str, str], dict[str, Any]]) -> list[Path]:
    """Write the figures; ``groups[(scenario, iod, filter)]`` holds the run summaries (dicts, see
    :meth:`cistrack.evaluation.run_summary.RunSummary.to_dict`), ``rows`` the report rows with ``hdr_ks`` and
    ``hdr_ks_p``. Groups without an HDR level (no truth) are left out. Returns the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    from cistrack.studies.report_plots import save_figure

    by_case: dict[tuple[str, str], dict[str, np.ndarray]] = {}
    for (sc, iod, flt), sums in groups.items():
        lv = _levels(sums)
        if lv.size:
            by_case.setdefault((sc, iod), {})[flt] = lv
    edges = np.linspace(0.0, 1.0, HDR_BINS + 1)
    files: list[Path] = []
    for (sc, iod), filters in sorted(by_case.items()):
        fig, ax = plt.subplots(figsize=(7.0, 4.8), layout="constrained")
        width = (edges[1] - edges[0]) / (len(filters) + 1)  # side by side within each bin, a gap between bins
        for ci, (flt, lv) in enumerate(sorted(filters.items())):
            r = rows.get((sc, iod, flt), {})
            d, p = r.get("hdr_ks"), r.get("hdr_ks_p")
            ks = f"KS D = {d:.2f}, p = {p:.2g}" if d is not None and p is not None else "KS -"
            counts, _ = np.histogram(lv, bins=edges)
            ax.bar(edges[:-1] + (ci + 0.5) * width + 0.5 * width, counts, width=width, color=f"C{ci}",
                   label=f"{flt}: {lv.size} runs, {ks}")
            ax.axhline(lv.size / HDR_BINS, color=f"C{ci}", lw=0.9, ls="--")
        ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))  # counts of runs
        ax.plot([], [], color="0.3", lw=0.9, ls="--", label="uniform (a calibrated filter): runs / bins")
        ax.set_xlim(0.0, 1.0)
        ax.set_xlabel("truth's final highest-density level (0 = at the mode, 1 = far in the tails)")
        ax.set_ylabel("runs")
        ax.set_title(f"Final truth HDR level on {sc}, IOD {iod}", fontsize=10)
        # below the axes: inside, the legend hides the tops of the bars it describes
        fig.legend(fontsize=8, frameon=False, loc="outside lower center", ncol=2)
        ax.grid(True, alpha=0.3)
        files.extend(save_figure(fig, rep_dir / f"{sc}__{iod}__hdr"))
    return files
