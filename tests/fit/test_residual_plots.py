"""The post-fit residual figure (core/fitting/residual_plots.py): its legend hides no residual."""
from __future__ import annotations

from datetime import datetime, timezone

import numpy as np

from cistrack.fitting.residual_plots import plot_residuals, residual_figure
from cistrack.least_squares.residual_table import residual_table
from cistrack.units import ARCSEC_RAD


def _table(n: int = 40):
    rng = np.random.default_rng(5)
    sigma = np.full((n, 2), 1.0 * ARCSEC_RAD)
    res = rng.normal(0.0, 1.0, (n, 2)) * sigma
    res[:3] = 2.2 * sigma[:3]  # points high at the arc's start: where a legend in the panel sat
    rejected = np.zeros(n, dtype=bool)
    rejected[5] = True
    return residual_table(np.linspace(0.0, 0.2, n), np.array(["J04"] * n), np.array(["radec"] * n),
                          ("right_ascension", "declination"), np.full((n, 2), 0.3), res, sigma, rejected)


def _boxes(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    r = fig.canvas.get_renderer()
    axes = [ax.get_window_extent(r) for ax in fig.axes]
    legend = fig.axes[0].get_legend().get_window_extent(r)
    return axes, legend


def test_the_legend_overlaps_no_panel():
    fig = residual_figure(_table(), "J04", datetime(2026, 1, 1, tzinfo=timezone.utc))
    axes, legend = _boxes(fig)
    assert [a.overlaps(legend) for a in axes] == [False] * len(axes)


def test_the_legend_lies_inside_the_figure():
    fig = residual_figure(_table(), "J04", datetime(2026, 1, 1, tzinfo=timezone.utc))
    _, legend = _boxes(fig)
    w, h = fig.canvas.get_width_height()
    assert 0 <= legend.x0 and legend.x1 <= w and 0 <= legend.y0 and legend.y1 <= h


def test_a_png_and_an_svg_are_written_per_site(tmp_path):
    written = plot_residuals(tmp_path, _table(), datetime(2026, 1, 1, tzinfo=timezone.utc))
    assert sorted(p.name for p in written) == ["residuals-J04.png", "residuals-J04.svg"]


def test_a_gross_rejected_residual_is_marked_at_the_edge_and_does_not_set_the_axis():
    n = 40
    sigma = np.full((n, 2), 1.0 * ARCSEC_RAD)
    res = np.random.default_rng(6).normal(0.0, 1.0, (n, 2)) * sigma
    res[5] = [-3000.0 * ARCSEC_RAD, 900.0 * ARCSEC_RAD]  # one observation a degree off, rejected
    rejected = np.arange(n) == 5
    t = residual_table(np.linspace(0.0, 0.2, n), np.array(["J04"] * n), np.array(["radec"] * n),
                       ("right_ascension", "declination"), np.full((n, 2), 0.3), res, sigma, rejected)
    fig = residual_figure(t, "J04", datetime(2026, 1, 1, tzinfo=timezone.utc))
    for j, ax in enumerate(fig.axes):
        lo, hi = ax.get_ylim()
        assert hi < 10.0 and lo > -10.0  # the used ones (about 1 arcsec) and the 3-sigma band fill it
        assert f"{t.o_c[5, j]:,.0f}" in [a.get_text() for a in ax.texts]
