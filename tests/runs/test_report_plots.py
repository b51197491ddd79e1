"""Report figures: percentiles across seeds of step series, the chi-square band, the files."""
from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest

from cistrack.studies.report_plots import FORMATS, band_over_seeds, loss_marks, nees_band, plot_study


def test_each_seed_is_held_between_its_steps_and_percentiles_are_taken_across_seeds():
    grid = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.5])
    series = [(np.array([0.0, 1.0, 2.0]), np.array([10.0, 20.0, 30.0])),
              (np.array([0.0, 2.0]), np.array([0.0, 40.0])),
              (np.array([0.5, 1.5]), np.array([5.0, 7.0]))]
    # held values per seed on the grid (NaN outside a seed's steps)
    held = np.array([[10, 10, 20, 20, 30, np.nan],
                     [0, 0, 0, 0, 40, np.nan],
                     [np.nan, 5, 5, 7, np.nan, np.nan]])
    lo, mid, hi = band_over_seeds(series, grid)
    for j in range(5):
        col = held[:, j][np.isfinite(held[:, j])]
        assert mid[j] == pytest.approx(np.median(col))
        assert lo[j] == pytest.approx(np.percentile(col, 5)) and hi[j] == pytest.approx(np.percentile(col, 95))
    assert np.isnan(mid[5])


def test_the_nees_band_is_the_central_90_percent_of_chi_square_6():
    lo, hi = nees_band(6, 0.90)
    assert lo == pytest.approx(1.635, abs=1e-3) and hi == pytest.approx(12.592, abs=1e-3)  # textbook table


def _table(seed: int, lost: bool) -> pa.Table:
    t = np.linspace(0.0, 2.0, 9)
    rng = np.random.default_rng(seed)
    return pa.table({"t_days": t, "kind": ["initial"] + ["update"] * 8,
                     "pos_err_km": 1e4 * np.exp(-2 * t) * (1 + 0.1 * rng.random(9)),
                     "sigma_pos_km": 2e4 * np.exp(-2 * t), "nees": 6 * (1 + 0.3 * rng.standard_normal(9)) ** 2,
                     "entropy": 20 - 15 * t * (3 if lost else 1)})


def test_the_figure_is_written_as_png_svg_and_pdf_and_names_the_filters(tmp_path):
    groups = {("quick", "noisy-range", f): {"tables": [_table(s, f == "ukf") for s in (1, 2, 3)],
                                            "summaries": [{"custody_kept": f != "ukf", "custody_lost_t_days": 1.2}] * 3}
              for f in ("pgm", "ukf")}
    files = plot_study(groups, tmp_path, "demo")
    assert sorted(f.suffix for f in files) == sorted(f".{e}" for e in FORMATS)
    assert all(f.stat().st_size > 5000 for f in files)
    svg = next(f for f in files if f.suffix == ".svg").read_text()
    assert "pgm vs ukf on quick" in svg and "custody lost (3 of 3 runs)" in svg


def test_the_nees_axis_keeps_its_tick_labels_when_a_diverged_filter_spans_ten_decades(tmp_path):
    def diverged(seed):
        t = _table(seed, True)
        return t.set_column(t.column_names.index("nees"), "nees", pa.array(np.logspace(0, 10, 9)))

    groups = {("quick", "noisy-range", "pgm"): {"tables": [diverged(s) for s in (1, 2, 3)],
                                                "summaries": [{"custody_kept": False, "custody_lost_t_days": 1.2}] * 3}}
    svg = next(f for f in plot_study(groups, tmp_path, "demo") if f.suffix == ".svg").read_text()
    assert "1e+06" in svg and "1e+08" in svg  # decade ticks of the NEES panel (none were drawn before)


def _collapsed(seed: int) -> pa.Table:
    """A bootstrap particle filter's collapse: sigma 1e-9 km, NEES 1e38, entropy -1e8."""
    t = _table(seed, True)
    for name, values in (("nees", np.full(9, 1e38)), ("sigma_pos_km", np.full(9, 1e-9)), ("entropy", np.full(9, -1e8))):
        t = t.set_column(t.column_names.index(name), name, pa.array(values))
    return t


def test_a_diverged_filter_never_sets_the_axes_and_is_named_off_scale(tmp_path):
    diverged = {"custody_kept": False, "custody_lost_t_days": 0.3, "verdict": {"kind": "diverged"}}
    groups = {("quick", "noisy-range", "pgm"): {"tables": [_table(s, False) for s in (1, 2, 3)],
                                                "summaries": [{"custody_kept": True, "verdict": {"kind": "tracking"}}] * 3},
              ("quick", "noisy-range", "sir"): {"tables": [_collapsed(s) for s in (1, 2, 3)], "summaries": [diverged] * 3}}
    svg = next(f for f in plot_study(groups, tmp_path, "demo") if f.suffix == ".svg").read_text()
    assert "sir: diverged 3 of 3 runs, median (clipped)" in svg
    for tick in ("1e+36", "1e+30", "1e+20", "-1e+08", "10^{-9}"):  # the collapse's scale on no axis
        assert f">{tick}<" not in svg


def test_the_nees_reference_line_is_the_chi_square_median_beside_the_plotted_medians(tmp_path):
    groups = {("quick", "noisy-range", "pgm"): {"tables": [_table(s, False) for s in (1, 2, 3)],
                                                "summaries": [{"custody_kept": True}] * 3}}
    svg = next(f for f in plot_study(groups, tmp_path, "demo") if f.suffix == ".svg").read_text()
    assert "chi-square(6) median 5.35" in svg


def test_when_every_filter_diverged_their_medians_set_every_panel_beside_the_bound(tmp_path):
    """The information bound alone sets no panel: the entropy and NEES panels hold the medians."""
    def with_bound(seed):
        t = _table(seed, True)
        return t.append_column("bound_pos_km", pa.array(5e3 * np.exp(-2 * np.linspace(0.0, 2.0, 9))))

    diverged = {"custody_kept": False, "custody_lost_t_days": 0.3, "verdict": {"kind": "diverged"}}
    groups = {("quick", "noisy-range", f): {"tables": [with_bound(s) for s in (1, 2, 3)], "summaries": [diverged] * 3}
              for f in ("pgm", "ukf")}
    svg = next(f for f in plot_study(groups, tmp_path, "demo") if f.suffix == ".svg").read_text()
    assert ">\u221260<" in svg  # the entropy panel reaches the medians' -70 nats


def test_custody_losses_at_one_time_are_one_triangle_with_their_count():
    times, counts = loss_marks([1.2, 2.5, 1.2, 1.2004, 2.5, 1.21])  # to the default 0.001 d
    assert times == pytest.approx([1.2, 1.21, 2.5]) and list(counts) == [3, 1, 2]
    assert loss_marks([])[0].size == 0


def test_each_filter_draws_its_losses_in_its_own_row_with_their_count(tmp_path):
    groups = {("quick", "noisy-range", f): {"tables": [_table(s, True) for s in (1, 2, 3)],
                                            "summaries": [{"custody_kept": False, "custody_lost_t_days": 1.2}] * 3}
              for f in ("enkf", "ukf")}
    svg = next(f for f in plot_study(groups, tmp_path, "demo") if f.suffix == ".svg").read_text()
    assert "enkf: custody lost (3 of 3 runs)" in svg and "ukf: custody lost (3 of 3 runs)" in svg
    assert svg.count("> 3<") + svg.count(">\u00a03<") + svg.count(" 3</text>") >= 2  # the count beside each row
