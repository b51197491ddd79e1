"""``Run.plot()``: one figure of a run, error, sigma, NEES with its chi-square band, entropy; a run
without a truth plots what it has (sigma, NIS with its band, entropy). Real small quick runs."""
from __future__ import annotations

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

import cistrack as ct
from cistrack.plugins.readers.csv_file import write_measurements
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.studies.report_plots import nees_band


def _labels(fig) -> list[str]:
    return [ax.get_ylabel() for ax in fig.axes]


def _ax(fig, label: str):
    return next(ax for ax in fig.axes if ax.get_ylabel().startswith(label))


def _band(ax) -> tuple[float, float] | None:
    """The y extent of the horizontal band (axhspan) drawn on ``ax``, if any."""
    for patch in ax.patches:
        if isinstance(patch, matplotlib.patches.Rectangle):
            return patch.get_y(), patch.get_y() + patch.get_height()
        ys = np.asarray(patch.get_xy())[:, 1]
        return float(ys.min()), float(ys.max())
    return None


@pytest.fixture(scope="module")
def quick_figure():
    run = ct.run("quick", seed=2)
    fig = run.plot()
    yield run, fig
    plt.close(fig)


def test_plot_returns_a_figure_with_error_sigma_nees_and_entropy_panels(quick_figure):
    _, fig = quick_figure
    assert isinstance(fig, matplotlib.figure.Figure)
    assert _labels(fig) == ["position error (km)", "1-sigma position (km)", "NEES", "entropy (nats)"]


def test_error_and_sigma_spanning_decades_are_on_log_axes(quick_figure):
    _, fig = quick_figure
    assert _ax(fig, "position error").get_yscale() == "log"
    assert _ax(fig, "1-sigma position").get_yscale() == "log"
    assert _ax(fig, "entropy").get_yscale() == "linear"


def test_nees_panel_draws_the_chi_square_5_95_band_of_6_dof(quick_figure):
    _, fig = quick_figure
    band = _band(_ax(fig, "NEES"))
    assert band == pytest.approx(nees_band(6))


def test_the_sigma_panel_shows_the_band_of_the_per_axis_sigmas(quick_figure):
    run, fig = quick_figure
    ax = _ax(fig, "1-sigma position")
    assert any("per-axis sigma" in t.get_text() for t in ax.get_legend().get_texts())
    lo, hi = ax.get_ylim()
    s = run.steps
    assert lo <= s[["sigma_x_km", "sigma_y_km", "sigma_z_km"]].min().min() and hi >= s["sigma_pos_km"].max()


def test_the_title_names_the_run_and_its_verdict(quick_figure):
    run, fig = quick_figure
    assert fig._suptitle.get_text() == f"{run.run_id}: {run.verdict.kind}"


def test_a_custody_loss_is_marked_on_every_panel():
    run = ct.run("quick", settings={"duration_days": 1.4, "custody.loglik_threshold": 50.0})
    assert not run.summary.custody_kept
    fig = run.plot()
    lost = run.summary.custody_lost_t_days
    for ax in fig.axes:
        assert any(np.allclose(line.get_xdata(), lost) and line.get_linestyle() == ":" for line in ax.get_lines())
    assert any(t.get_text().startswith("custody lost") for t in fig.axes[0].get_legend().get_texts())
    plt.close(fig)


def test_a_run_without_a_truth_plots_sigma_nis_with_its_band_and_entropy(tmp_path):
    sim = run_scenario(load_scenario("quick").with_overrides({"duration_days": 1.4}), seed=1)
    obs = tmp_path / "obs.csv"
    write_measurements(obs, sim.context.measurements, "2026-01-01T00:00:00Z")
    run = ct.run("quick", settings={"duration_days": 1.4, "measurements.file": str(obs)})
    assert run.verdict.kind == "no-truth"
    fig = run.plot()
    assert _labels(fig) == ["1-sigma position (km)", "NIS", "entropy (nats)"]
    assert _band(_ax(fig, "NIS")) == pytest.approx(nees_band(2))
    plt.close(fig)
