"""Maneuver scores of a study: per truth burn (detected, delay, pass, delta-v error over sigma), per
run (false alarms, custody) and per report group (P(detect) with Wilson intervals, ...), from
hand-built summaries; then the report's Maneuvers table and figures on one small real study."""
from __future__ import annotations

import concurrent.futures as cf
import csv
import json
from pathlib import Path

import numpy as np
import pytest

from cistrack.studies.maneuver_scores import (GroupRuns, group_maneuver_scores, has_maneuvers, maneuver_markdown,
                                              maneuver_rows, maneuver_text, score_run, update_rows)

# Example 1's updates (seed 1): passes 1-6; the burn at 3.62 d falls between passes 3 and 4.
_PASSES = {1: [1.09, 1.12, 1.16, 1.20], 2: [1.96, 1.99, 2.03, 2.06, 2.10], 3: [2.87, 2.91, 2.95, 2.98, 3.01],
           4: [3.97, 3.99, 4.03, 4.07, 4.10], 5: [5.07, 5.11, 5.15, 5.18, 5.21], 6: [6.20, 6.22, 6.26, 6.29, 6.33]}
UPDATES = [{"t_days": t, "pass_index": float(p)} for p, ts in _PASSES.items() for t in ts]


def _episode(t, dv=None, sigma=None, confirmed=None):
    return {"t_days": t, "detections": 1, "delta_v_ms": dv, "delta_v_sigma_ms": sigma,
            "confirmed": dv is not None if confirmed is None else confirmed, "detector": "mixture-likelihood"}


def _summary(episodes=(), burns=((3.62, 1.0),), kept=True):
    return {"maneuvers": list(episodes), "custody_kept": kept,
            "truth_maneuvers": [{"t_days": t, "delta_v_ms": dv, "delta_v_vector_ms": [0.0, dv, 0.0], "label": "b"}
                                for t, dv in burns]}


def test_a_burn_detected_in_the_next_pass_scores_its_delay_pass_and_delta_v_error():
    s = score_run(_summary([_episode(4.03, dv=1.05, sigma=0.1)]), UPDATES)
    (b,) = s.burns
    assert (b.detected, b.pass_offset, b.confirmed) == (True, 0, True)
    assert b.delay_days == pytest.approx(4.03 - 3.62) and b.dv_error_sigma == pytest.approx(0.5)
    assert (s.false_alarms, s.repeats, s.custody_kept) == (0, 0, True)


def test_a_detection_a_pass_later_is_offset_one_and_an_unconfirmed_one_has_no_delta_v_error():
    (b,) = score_run(_summary([_episode(5.11, confirmed=False)]), UPDATES).burns
    assert (b.detected, b.pass_offset, b.confirmed, b.dv_error_sigma) == (True, 1, False, None)
    (b,) = score_run(_summary([_episode(6.26, dv=2.0, sigma=float("nan"))]), UPDATES).burns
    assert (b.pass_offset, b.dv_error_sigma) == (2, None)  # NaN (null) sigma: no error over sigma


def test_episodes_before_the_first_burn_are_false_alarms_and_later_ones_in_its_window_repeats():
    s = score_run(_summary([_episode(2.03), _episode(4.03, dv=1.0, sigma=0.2), _episode(6.22)]), UPDATES)
    assert (s.false_alarms, s.repeats) == (1, 1)
    assert s.burns[0].detected and s.burns[0].delay_days == pytest.approx(0.41)


def test_two_burns_each_take_the_episodes_up_to_the_next_and_a_burn_after_the_last_update_is_not_scored():
    s = score_run(_summary([_episode(4.03), _episode(5.15)], burns=((3.62, 1.0), (4.5, 0.3), (7.0, 0.1))), UPDATES)
    assert [(b.t_days, b.detected, b.pass_offset) for b in s.burns] == [(3.62, True, 0), (4.5, True, 0)]
    assert (s.false_alarms, s.repeats) == (0, 0)
    s = score_run(_summary([_episode(5.15)], burns=((3.62, 1.0), (4.5, 0.3))), UPDATES)
    assert [b.detected for b in s.burns] == [False, True]


def test_a_run_whose_truth_does_not_burn_counts_every_episode_as_a_false_alarm():
    s = score_run(_summary([_episode(2.0), _episode(5.1)], burns=(), kept=False), UPDATES)
    assert (s.burns, s.false_alarms, s.custody_kept) == ([], 2, False)
    assert not has_maneuvers([_summary(burns=())]) and has_maneuvers([_summary([_episode(2.0)], burns=())])
    assert has_maneuvers([_summary()])


def test_a_swept_burn_of_zero_is_no_burn_its_detections_are_false_alarms():
    """A sweep of delta_v_ms from 0: the 0 m/s "burn" is not flown, so it is not a missed detection."""
    s = score_run(_summary([_episode(4.03)], burns=((3.62, 0.0),)), UPDATES)
    assert (s.burns, s.false_alarms) == ([], 1)


def test_update_rows_keeps_the_update_steps_of_a_steps_table_in_time_order():
    import pyarrow as pa

    t = pa.table({"t_days": [2.0, 1.0, 1.5, 3.0], "kind": ["update", "update", "predict", "update"],
                  "pass_index": [2.0, 1.0, None, None]})
    assert update_rows(t) == [{"t_days": 1.0, "pass_index": 1.0}, {"t_days": 2.0, "pass_index": 2.0},
                              {"t_days": 3.0, "pass_index": None}]


def test_group_scores_with_wilson_intervals_median_delay_and_false_alarm_runs():
    from scipy.stats import binomtest

    runs = [score_run(_summary([_episode(4.03, dv=1.05, sigma=0.1)]), UPDATES),          # next pass, within 3 sigma
            score_run(_summary([_episode(5.11, dv=1.6, sigma=0.1)]), UPDATES),           # a pass later, 6 sigma off
            score_run(_summary([_episode(2.0), _episode(6.26)], kept=False), UPDATES),   # false alarm, 2 passes late
            score_run(_summary([]), UPDATES)]                                            # missed
    g = group_maneuver_scores(runs)
    assert (g["runs"], g["burns"], g["detected"], g["next_pass"], g["two_passes"]) == (4, 4, 3, 1, 2)
    for key, k in (("p_detect", 3), ("p_next_pass", 1), ("p_two_passes", 2)):
        ci = binomtest(k, 4).proportion_ci(0.95, method="wilson")
        assert (g[key], g[f"{key}_lo"], g[f"{key}_hi"]) == pytest.approx((k / 4, ci.low, ci.high))
    assert g["median_delay_days"] == pytest.approx(np.median([4.03 - 3.62, 5.11 - 3.62, 6.26 - 3.62]))
    assert (g["confirmed"], g["within_3_sigma"], g["within_3_sigma_share"]) == (2, 1, 0.5)
    ci = binomtest(1, 4).proportion_ci(0.95, method="wilson")
    assert (g["false_alarm_runs"], g["false_alarm_rate"], g["false_alarm_lo"], g["false_alarm_hi"]) == \
        pytest.approx((1, 0.25, ci.low, ci.high))
    assert (g["custody_kept"], g["custody_runs"], g["false_alarms"]) == (3, 4, 1)


def test_a_group_without_burns_has_no_detection_share_but_its_false_alarm_rate():
    g = group_maneuver_scores([score_run(_summary([_episode(2.0)], burns=()), UPDATES),
                               score_run(_summary([], burns=()), UPDATES)])
    assert (g["burns"], g["p_detect"], g["median_delay_days"], g["false_alarm_rate"]) == (0, None, None, 0.5)


def _rows():
    """Hand-built groups of a swept study: dv x response for PGM, and a no-burn scenario."""
    groups = {}
    for dv, hit in ((0.01, None), (0.3, 5.11), (1.0, 4.03)):
        for resp in ("none", "inflate"):
            label = f"example-1-burn[dv={dv:g},resp={resp}]"
            eps = [_episode(hit, dv=dv, sigma=0.1)] if hit else []
            groups[(label, "uniform-range", "pgm")] = GroupRuns(
                [_summary(eps, burns=((3.62, dv),))] * 3, [UPDATES] * 3,
                (("truth.maneuvers.delta_v_ms", dv), ("maneuvers.response", resp)))
    groups[("example-1", "uniform-range", "pgm")] = GroupRuns([_summary([_episode(2.0)], burns=()),
                                                              _summary([], burns=())], [UPDATES] * 2)
    return maneuver_rows(groups)


def test_maneuver_rows_name_the_groups_burn_size_and_response_and_render_as_tables():
    rows = _rows()
    r = next(r for r in rows if r["scenario"] == "example-1-burn[dv=0.3,resp=inflate]")
    assert (r["delta_v_ms"], r["response"], r["_base"], r["burns"], r["detected"], r["next_pass"]) == \
        (0.3, "inflate", "example-1-burn", 3, 3, 0)
    r0 = next(r for r in rows if r["scenario"] == "example-1")
    assert (r0["delta_v_ms"], r0["burns"], r0["false_alarm_runs"], r0["runs"]) == (None, 0, 1, 2)
    md = "\n".join(maneuver_markdown(rows))
    assert "## Maneuvers" in md and "| example-1-burn[dv=1,resp=none] | uniform-range | pgm | 3 | 3 | 3/3 [" in md
    text = maneuver_text(rows)
    assert all(len(line) <= 120 for line in text) and "scenario example-1-burn[dv=0.3,resp=inflate]:" in text


def test_rows_come_in_the_order_of_the_swept_values_not_of_their_text():
    groups = {(f"b[dv={dv:g}]", "u", "pgm"): GroupRuns([_summary(burns=((3.62, dv),))], [UPDATES],
                                                         (("truth.maneuvers.delta_v_ms", dv),))
              for dv in (10.0, 0.3, 1.0, 3.0)}
    groups[("a", "u", "pgm")] = GroupRuns([_summary(burns=())], [UPDATES])
    assert [r["scenario"] for r in maneuver_rows(groups)] == ["a", "b[dv=0.3]", "b[dv=1]", "b[dv=3]", "b[dv=10]"]


def test_the_detection_curve_has_a_line_per_filter_and_response_on_a_log_axis_of_the_swept_values(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cistrack.studies import report_plots
    from cistrack.studies.report_plots import detection_lines, plot_false_alarms, plot_maneuver_detection

    rows = _rows()
    lines = detection_lines(rows)
    assert list(lines) == ["pgm, response inflate", "pgm, response none"]
    assert [r["delta_v_ms"] for r in lines["pgm, response none"]] == [0.01, 0.3, 1.0]
    seen = {}
    real_save = report_plots.save_figure

    def keep(fig, stem):
        seen[stem.name] = [(ax.get_xscale(), list(ax.get_xticks()), ax.get_title()) for ax in fig.axes]
        return real_save(fig, stem)

    report_plots.save_figure = keep
    try:
        files = plot_maneuver_detection(rows, tmp_path, "s") + plot_false_alarms(rows, tmp_path, "s")
    finally:
        report_plots.save_figure = real_save
    assert sorted(f.name for f in files) == sorted(f"{n}.{e}" for n in ("maneuver_detection", "maneuver_false_alarms")
                                                   for e in ("png", "svg", "pdf"))
    assert all(f.stat().st_size > 0 for f in files)
    (s1, t1, title1), (s2, t2, _) = seen["maneuver_detection"]
    assert (s1, s2) == ("log", "log") and t1 == pytest.approx([0.01, 0.3, 1.0]) and "P(detect)" in title1
    assert plot_maneuver_detection([r for r in rows if not r["burns"]], tmp_path) == []
    plt.close("all")


# --- one small real study: Example 1 (no burn) and Example 1 with a 0.01 and a 1 m/s burn, PGM, seed 1 ---

_STUDY = """
name = "maneuver-scores-test"
scenarios = [{ name = "example-1", sweep = false }, "example-1-burn"]
filters = [{ name = "pgm", n_particles = 2000, n_components = 4 }]
iod = [{ name = "uniform-range", n_particles = 2000 }]
seeds = [1]
sweep = { "truth.maneuvers.delta_v_ms" = [0.01, 1.0] }
"""


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    from cistrack.studies.report import report_study
    from cistrack.studies.study import run_study

    d = tmp_path_factory.mktemp("maneuver_study")
    (d / "study.toml").write_text(_STUDY)
    res = run_study(d / "study.toml", out_dir=d / "out", executor=cf.ThreadPoolExecutor(1), progress=False)
    assert res["failed"] == 0 and res["total"] == 3
    return d / "out", report_study(d / "study.toml", out_dir=d / "out")


def test_a_real_study_reports_its_maneuvers_table_csv_and_figures(small_study):
    out, rep = small_study
    names = {Path(f).name for f in rep["files"]}
    assert {"maneuvers.csv", "maneuver_detection.png", "maneuver_false_alarms.pdf",
            "example-1-burn[dv=0.01]__uniform-range.png"} <= names
    with open(out / "report" / "maneuvers.csv") as fh:
        rows = {r["scenario"]: r for r in csv.DictReader(fh)}
    assert set(rows) == {"example-1", "example-1-burn[dv=0.01]", "example-1-burn[dv=1]"}
    assert (rows["example-1"]["burns"], rows["example-1-burn[dv=1]"]["burns"]) == ("0", "1")
    assert rows["example-1-burn[dv=1]"]["delta_v_ms"] == "1.0" and rows["example-1-burn[dv=1]"]["response"] == "inflate"
    assert "## Maneuvers" in (out / "report" / "summary.md").read_text()
    assert "Maneuvers (detected and false-alarm runs" in rep["text"]


def test_a_real_runs_score_agrees_with_its_manifest_and_steps(small_study):
    from cistrack.results.store import read_steps

    out, rep = small_study
    run = out / "runs" / "example-1-burn[dv=1]__pgm__uniform-range__seed1"
    summary = json.loads((run / "manifest.json").read_text())["summary"]
    updates = update_rows(read_steps(run))
    s = score_run(summary, updates)
    (b,) = s.burns
    eps = [e for e in summary["maneuvers"] if e["t_days"] > 3.62]
    assert b.detected == bool(eps)
    row = next(r for r in rep["maneuver_rows"] if r["scenario"] == "example-1-burn[dv=1]")
    assert row["detected"] == int(b.detected) and row["false_alarm_runs"] == int(s.false_alarms > 0)
    if eps:
        first_after = next(u for u in updates if u["t_days"] > 3.62)
        at = next(u for u in updates if abs(u["t_days"] - eps[0]["t_days"]) < 1e-6)
        assert b.pass_offset == at["pass_index"] - first_after["pass_index"]
        assert b.delay_days == pytest.approx(eps[0]["t_days"] - 3.62)
