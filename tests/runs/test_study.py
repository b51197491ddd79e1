"""Studies: resumable, executor-independent, reported."""
from __future__ import annotations

import concurrent.futures as cf
import json
import shutil
from pathlib import Path

import pytest

from cistrack.errors import CistrackError, ConfigError
from cistrack.results.store import read_manifest, read_steps
from cistrack.studies.study import plan_runs, run_study
from cistrack.studies.report import report_study


def _tables(out: Path) -> dict[str, list]:
    return {d.name: read_steps(d).drop_columns([c for c in read_steps(d).column_names if c.startswith("time_")]).to_pylist()
            for d in sorted((out / "runs").iterdir())}


def test_resumed_study_runs_only_what_is_missing_and_equals_an_uninterrupted_one(tiny_study, tmp_path):
    full = tmp_path / "full"
    res = run_study(tiny_study, out_dir=full, executor=cf.ThreadPoolExecutor(1), progress=False)
    assert (res["completed"], res["failed"]) == (3, 0)
    part = tmp_path / "part"
    shutil.copytree(full, part)
    runs = sorted((part / "runs").iterdir())
    shutil.rmtree(runs[0])                                  # never started
    (runs[1] / "steps.parquet").unlink()                    # killed mid-way
    man = read_manifest(runs[1])
    man["status"] = "running"
    (runs[1] / "manifest.json").write_text(json.dumps(man))
    res2 = run_study(tiny_study, out_dir=part, executor=cf.ThreadPoolExecutor(1), progress=False)
    assert (res2["completed"], res2["skipped"]) == (2, 1)
    assert _tables(part) == _tables(full)


def test_same_seed_gives_identical_results_under_process_and_dask_executors(tiny_study, tmp_path):
    pytest.importorskip("distributed")
    a, b = tmp_path / "proc", tmp_path / "dask"
    run_study(tiny_study, out_dir=a, workers=2, progress=False)
    run_study(tiny_study, out_dir=b, workers=2, dask="local", progress=False)
    assert _tables(a) == _tables(b)


def test_report_writes_table_markdown_and_plots_and_says_who_kept_custody(tiny_study, tmp_path):
    out = tmp_path / "s"
    run_study(tiny_study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False)
    rep = report_study(tiny_study, out_dir=out)
    names = {Path(f).name for f in rep["files"]}
    assert {"summary.csv", "summary.md"} <= names and any(n.endswith(".png") for n in names)
    assert rep["rows"][0]["runs"] == 3
    assert "pgm with noisy-range IOD on quick" in rep["text"]
    assert {".png", ".svg", ".pdf"} <= {Path(f).suffix for f in rep["files"]}
    _check_spread_anees_and_wall_time_against_the_runs(rep["rows"][0], out)
    _check_verdict_counts_and_flagged_runs_against_the_runs(rep["rows"][0], out)
    _check_calibration_against_the_runs(rep, out)


def _check_calibration_against_the_runs(rep, out):
    """Custody interval, final ANEES and bounds, HDR KS and diverged count recomputed with scipy
    from the manifests; the Markdown table, the terminal text and the histogram figure."""
    import numpy as np
    from scipy.stats import binomtest, chi2, kstest

    row = rep["rows"][0]
    sums = [read_manifest(d)["summary"] for d in sorted((out / "runs").iterdir())]
    kept = sum(1 for s in sums if s["verdict"]["kind"] in ("tracking", "not-converged"))
    ci = binomtest(kept, len(sums)).proportion_ci(0.95, method="wilson")
    assert (row["custody_ci_lo"], row["custody_ci_hi"]) == pytest.approx((ci.low, ci.high))
    nees = [s["final"]["nees"] for s in sums]
    n = len(nees)
    assert row["final_anees"] == pytest.approx(np.mean(nees)) and row["final_anees_runs"] == n
    assert (row["final_anees_lo"], row["final_anees_hi"]) == pytest.approx(
        (chi2.ppf(0.025, 6 * n) / n, chi2.ppf(0.975, 6 * n) / n))
    ks = kstest([s["final"]["hdr_level"] for s in sums], "uniform")
    assert (row["hdr_ks"], row["hdr_ks_p"]) == pytest.approx((ks.statistic, ks.pvalue))
    assert row["diverged_runs"] == sum(1 for s in sums if s["verdict"]["kind"] == "diverged")
    md = (out / "report" / "summary.md").read_text()
    assert "## Calibration" in md and "custody rate [Wilson 95 %]" in md and f"D = {row['hdr_ks']:.2f}" in md
    assert "Calibration (95 %; the final ANEES averages each run's last NEES):" in rep["text"]
    with open(out / "report" / "summary.csv") as fh:
        header = fh.readline().strip().split(",")
    assert {"custody_ci_lo", "final_anees_lo", "hdr_ks_p", "diverged_runs"} <= set(header)
    assert (out / "report" / "quick__noisy-range__hdr.png").stat().st_size > 0


def _check_verdict_counts_and_flagged_runs_against_the_runs(row, out):
    verdicts = [read_manifest(d)["summary"]["verdict"] for d in sorted((out / "runs").iterdir())]
    kinds = [v["kind"] for v in verdicts]
    assert row["verdicts"] == "/".join(str(kinds.count(k)) for k in ("tracking", "not-converged", "lost", "diverged"))
    md = (out / "report" / "summary.md").read_text()
    assert "verdicts: tracking / not-converged / lost / diverged" in md
    for v in verdicts:
        if v["kind"] in ("diverged", "not-converged"):
            assert f"{v['kind']}: {v['reason']}" in md


def _check_spread_anees_and_wall_time_against_the_runs(row, out):
    import numpy as np

    runs = sorted((out / "runs").iterdir())
    nees = [v for d in runs for v, k in zip(read_steps(d).column("nees").to_pylist(), read_steps(d).column("kind").to_pylist())
            if k == "update"]
    assert row["anees_every_update"] == pytest.approx(np.mean(nees)) and row["anees_every_update_n"] == len(nees)
    walls = [read_manifest(d)["summary"]["wall_time_s"] for d in runs]
    assert row["wall_time_s"] == pytest.approx(np.median(walls))
    errs = [read_manifest(d)["summary"]["final"]["pos_err_km"] for d in runs]
    assert (row["pos_err_km_p5"], row["pos_err_km_p95"]) == pytest.approx(tuple(np.percentile(errs, [5, 95])))


def test_study_plan_rejects_unknown_filter_before_running(tmp_path):
    from cistrack.errors import ConfigError
    p = tmp_path / "bad.toml"
    p.write_text('scenarios = ["quick"]\nfilters = ["pgn"]\n')
    with pytest.raises(ConfigError, match="Did you mean 'pgm'"):
        plan_runs(p, tmp_path / "o")


def test_report_with_no_finished_run_exits_nonzero_and_writes_nothing(tiny_study, tmp_path, capsys):
    from cistrack.cli.main import main

    out = tmp_path / "never-run"
    assert main(["study", "report", str(tiny_study), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "nothing to report" in err and "cistrack study run" in err
    assert not (out / "report").exists()


def test_settings_apply_to_every_run_after_the_study_variants(tiny_study, tmp_path):
    _, specs, out = plan_runs(tiny_study, None, ["filter.n_particles=250", "duration_days=1.1"])
    assert out.name.startswith("tiny__set-")
    assert {s.overrides["filter"]["n_particles"] for s in specs} == {250}
    assert {s.overrides["duration_days"] for s in specs} == {1.1}
    assert {s.overrides["filter"]["name"] for s in specs} == {"pgm"}


def test_a_setting_that_a_study_variant_cannot_take_is_refused_naming_it(tiny_study):
    from cistrack.errors import ConfigError

    with pytest.raises(ConfigError, match=r"bogus.*--set filter.bogus=1"):
        plan_runs(tiny_study, None, ["filter.bogus=1"])


def test_builtin_calibration_study_reports_calibration_per_iod_under_process_and_dask_executors(tmp_path):
    """The built-in ``calibration`` study, cut to 2 seeds, 200 particles and 1.3 days (the first pass), run through
    local processes and a local Dask cluster: the same calibration for each IOD assumption."""
    pytest.importorskip("distributed")
    from importlib import resources

    text = (resources.files("cistrack.scenarios") / "studies" / "calibration.toml").read_text()
    assert "n_seeds = 100" in text
    study = tmp_path / "calibration.toml"
    study.write_text(text.replace("n_seeds = 100", "n_seeds = 2"))
    settings = ["filter.n_particles=200", "filter.n_components=2", "iod.n_particles=200", "duration_days=1.3"]
    reports = {}
    for name, kw in (("proc", {}), ("dask", {"dask": "local"})):
        out = tmp_path / name
        res = run_study(study, out_dir=out, workers=1, progress=False, settings=settings, **kw)
        assert (res["completed"], res["failed"]) == (6, 0)
        reports[name] = report_study(study, out_dir=out, settings=settings)
    keys = ("scenario", "iod", "filter", "runs", "custody_kept", "custody_ci_lo", "custody_ci_hi", "final_anees",
            "final_anees_lo", "final_anees_hi", "hdr_ks", "hdr_ks_p", "diverged_runs")
    rows = {n: [{k: r[k] for k in keys} for r in rep["rows"]] for n, rep in reports.items()}
    assert rows["proc"] == rows["dask"]
    assert {r["iod"] for r in rows["proc"]} == {"uniform-range", "noisy-range", "uniform-range-velocity-bound"}
    names = {Path(f).name for f in reports["dask"]["files"]}
    for r in rows["proc"]:
        assert r["runs"] == 2 and r["final_anees_lo"] < 6 < r["final_anees_hi"] and r["hdr_ks"] is not None
        assert {f"example-1__{r['iod']}.png", f"example-1__{r['iod']}__hdr.png"} <= names


def test_a_study_on_an_observation_file_reports_measurement_consistency_and_never_custody(observed_study):
    from cistrack.evaluation.residuals import residual_summary

    study, out = observed_study("observed", '{ name = "pgm", n_particles = 300, n_components = 2 }', "[1, 2]")
    rep = report_study(study, out_dir=out)
    md = (out / "report" / "summary.md").read_text()
    assert "custody" not in md.lower() and "custody" not in rep["text"].lower()
    assert "## Measurement consistency (no truth)" in md
    assert "Measurement consistency (95 %; no truth, so no calibration):" in rep["text"]
    row = rep["rows"][0]
    s = residual_summary([r for d in sorted((out / "runs").iterdir()) for r in read_steps(d).to_pylist()])
    assert row["custody_kept"] is None and row["nis_updates"] == s.nis_test.n
    assert (row["mean_nis"], row["nis_lo"], row["nis_hi"]) == pytest.approx((s.nis_test.mean, s.nis_test.lower,
                                                                              s.nis_test.upper))
    assert row["nis_outside_95_share"] == pytest.approx(s.share_outside_95)
    assert f"mean NIS {row['mean_nis']:.3g} over {s.nis_test.n} updates" in md


def test_report_without_seed_options_reports_the_seeds_study_run_ran(tiny_study, tmp_path):
    """`study run STUDY --n-seeds 1` then `study report STUDY`: the one seed's runs, all complete
    (it used to plan the file's three seeds and report a partial set)."""
    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=1)
    rep = report_study(tiny_study, out_dir=out)
    assert rep["missing"] == 0
    assert {r["runs"] for r in rep["rows"]} == {1}


def test_report_names_the_runs_that_did_not_finish(tiny_study, tmp_path):
    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=1)
    rep = report_study(tiny_study, out_dir=out, n_seeds=2)
    assert rep["missing"] > 0
    assert "not finished:" in rep["text"] and "seed2" in rep["text"]


def test_a_report_with_other_settings_than_the_runs_were_made_with_reports_none_of_them(tiny_study, tmp_path, capsys):
    """`study report DIR --set ...` had reported the runs made without it as complete."""
    from cistrack.cli.main import main

    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=1)
    assert main(["study", "report", str(out), "--set", "duration_days=1.2"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "nothing to report: the 1 finished run(s)" in err and "made with another scenario, settings" in err
    assert not (out / "report").exists()


def test_a_finished_run_the_study_now_plans_otherwise_is_named_and_not_reported(tiny_study, tmp_path):
    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=2)
    other = sorted((out / "runs").iterdir())[0]
    manifest = json.loads((other / "manifest.json").read_text())
    (other / "manifest.json").write_text(json.dumps({**manifest, "fingerprint": "made-otherwise"}))
    rep = report_study(tiny_study, out_dir=out, n_seeds=2)
    assert (rep["missing"], rep["stale"]) == (0, 1) and {r["runs"] for r in rep["rows"]} == {1}
    text = " ".join(rep["text"].split())
    assert "1 of 2 runs complete (not reported, made with another scenario" in text and other.name in text


def test_a_run_whose_step_table_was_overwritten_is_reported_missing_and_run_again(tiny_study, tmp_path):
    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=2)
    broken = sorted((out / "runs").iterdir())[0]
    (broken / "steps.parquet").write_text("not parquet")
    with pytest.raises(CistrackError, match="steps.parquet: not a readable step table"):
        read_steps(broken)
    rep = report_study(tiny_study, out_dir=out, n_seeds=2)
    assert rep["missing"] == 1 and broken.name in rep["text"]
    res = run_study(tiny_study, out_dir=out, workers=1, n_seeds=2)
    assert (res["completed"], res["failed"]) == (1, 0)
    assert read_steps(broken).num_rows > 1


def test_a_report_of_one_study_on_another_studys_directory_is_refused(tiny_study, tmp_path):
    out = tmp_path / "out"
    run_study(tiny_study, out_dir=out, workers=1, n_seeds=1)
    with pytest.raises(ConfigError, match="holds another study \\('tiny'\\), not 'quick-comparison'"):
        report_study("quick-comparison", out_dir=out)
