"""``ct.study(...)``: runs a study as ``cistrack study run`` does and gives its runs, a table with
one row per run and a figure. A real small study: quick-comparison (PGM and EnKF), one seed."""
from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

import cistrack as ct
from cistrack.api import Run, StudyResult
from cistrack.studies.study import plan_runs, run_study


@pytest.fixture(scope="module")
def small_study(tmp_path_factory) -> StudyResult:
    return ct.study("quick-comparison", n_seeds=1, settings={"duration_days": 2},
                    out=tmp_path_factory.mktemp("study") / "s", workers=1)


def test_study_returns_one_run_per_filter_and_seed(small_study):
    assert isinstance(small_study, StudyResult) and small_study.name == "quick-comparison"
    assert [(r.run_id, type(r)) for r in small_study.runs] == [
        ("quick__pgm__noisy-range__seed1", Run), ("quick__enkf__noisy-range__seed1", Run)]
    assert small_study.problems == ()


def test_the_table_has_one_row_per_run_with_its_verdict_and_final_metrics(small_study):
    t = small_study.table
    assert list(t["filter"]) == ["pgm", "enkf"] and list(t["seed"]) == [1, 1]
    assert {"scenario", "iod", "verdict", "reason", "pos_err_km", "nees", "entropy", "sigma_x_km"} <= set(t.columns)
    assert list(t["verdict"]) == [r.verdict.kind for r in small_study.runs]
    assert list(t["pos_err_km"]) == [r.final["pos_err_km"] for r in small_study.runs]


def test_the_settings_reach_every_run(small_study):
    assert all(r.steps["t_days"].max() <= 2.0 + 1e-9 for r in small_study.runs)


def test_running_the_study_again_reads_the_same_runs_back(small_study):
    again = ct.study("quick-comparison", n_seeds=1, settings={"duration_days": 2}, out=small_study.directory)
    assert [r.summary for r in again.runs] == [r.summary for r in small_study.runs]


def test_the_runs_are_those_of_the_study_plan_in_its_order(small_study):
    _, specs, directory = plan_runs("quick-comparison", small_study.directory, ["duration_days=2"], n_seeds=1)
    assert [r.run_id for r in small_study.runs] == [s.run_id for s in specs]
    assert small_study.directory == directory


def test_planning_a_study_twice_gives_the_same_plan(small_study):
    assert plan_runs(small_study.directory) == plan_runs(small_study.directory)


def test_run_study_returns_the_plan_it_ran(small_study):
    res = run_study(small_study.directory, workers=1, progress=False)
    assert res["specs"] == plan_runs(small_study.directory)[1]
    assert (res["skipped"], res["total"]) == (2, 2)


def test_running_the_study_folder_again_keeps_the_settings_it_was_run_with(small_study):
    ct.study(small_study.directory)
    _, specs, _ = plan_runs("quick-comparison", small_study.directory, ["duration_days=2"], n_seeds=1)
    assert plan_runs(small_study.directory)[1] == specs


def test_the_log_receives_the_line_the_command_line_prints(small_study):
    lines: list[str] = []
    ct.study(small_study.directory, log=lines.append)
    assert lines == [f"study 'quick-comparison': 0 runs completed, 2 already done, 0 failed -> {small_study.directory}"]


def test_the_study_figure_has_a_median_per_filter_and_the_nees_band(small_study):
    fig = small_study.plot()
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["position error (km)", "1-sigma position (km)", "NEES", "entropy (nats)"]
    legend = [t.get_text() for t in fig.axes[2].get_legend().get_texts()]
    assert any(x.startswith("pgm: median") for x in legend) and any(x.startswith("enkf: median") for x in legend)
    assert any(x.startswith("chi-square(6) 5-95 %") for x in legend)
    assert fig.axes[0].get_yscale() == "log"
    plt.close(fig)


def test_study_is_on_the_package():
    assert ct.study.__module__ == "cistrack.api" and ct.StudyResult is StudyResult


@pytest.mark.parametrize("kwargs, words", [({"n_seeds": 0}, "n_seeds: 0 is out of range"),
                                           ({"workers": 0}, "workers: 0 is out of range"),
                                           ({"first_seed": -5}, "first_seed: seed -5 is out of range")])
def test_bad_counts_are_refused_by_their_keyword_names(tmp_path, kwargs, words):
    with pytest.raises(ct.ConfigError) as exc:
        ct.study("quick-comparison", out=tmp_path / "s", **kwargs)
    assert str(exc.value).startswith(words) and "--" not in str(exc.value)
