"""Runs without a truth (a measurement file): their manifest stores the measurement consistency,
a degenerate or collapsed belief ends "diverged" with its reason (never "no-truth" alone), and
nothing they print or store speaks of custody (issue 16, item 3).

The runs are real: the built-in ``quick`` scenario simulated for 1.4 days (the first pass), its
measurements written to a CSV file and run again from the file through the CLI.
"""
from __future__ import annotations

import subprocess
import sys

import pytest

from cistrack.evaluation.residuals import consistency_summary, residual_summary
from cistrack.results.store import read_manifest, read_steps


def _cli_run(obs, out, *settings):
    args = [sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), "--set", "duration_days=1.4",
            "--set", f"measurements.file={obs}"]
    for s in settings:
        args += ["--set", s]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return proc


@pytest.fixture(scope="module")
def sir_file_run(obs_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("sir") / "run"
    return _cli_run(obs_file, out, "filter.name=sir", "filter.n_particles=500", "iod.n_particles=500"), out


def test_a_truthless_run_with_degenerate_weights_is_diverged_with_the_reason(sir_file_run):
    proc, out = sir_file_run
    v = read_manifest(out)["summary"]["verdict"]
    assert v["kind"] == "diverged" and v["reason"].startswith("degenerate weights (effective sample size")
    assert f"verdict: diverged at step {v['step']}" in proc.stdout and "degenerate weights" in proc.stdout
    assert "no-truth" not in proc.stdout


def test_a_truthless_diverged_run_prints_and_stores_no_custody(sir_file_run):
    proc, out = sir_file_run
    assert "custody" not in (proc.stdout + proc.stderr).lower()
    assert "custody" not in (out / "manifest.json").read_text().lower()
    assert "custody" not in read_steps(out).column_names
    assert "measurement consistency: mean NIS" in proc.stdout


def test_a_truthless_collapsed_belief_is_diverged_when_the_weight_rule_is_off(obs_file, tmp_path):
    out = tmp_path / "run"
    proc = _cli_run(obs_file, out, "filter.name=sir", "filter.n_particles=500", "iod.n_particles=500",
                    "custody.degenerate_ess=0")
    v = read_manifest(out)["summary"]["verdict"]
    assert v["kind"] == "diverged" and v["reason"].startswith("belief collapsed"), v
    assert "custody" not in proc.stdout.lower()


def test_truthless_measurements_far_outside_the_predicted_spread_are_diverged(obs_file, tmp_path):
    out = tmp_path / "run"
    _cli_run(obs_file, out, "filter.name=sir", "filter.n_particles=500", "iod.n_particles=500",
             "custody.degenerate_ess=0", "custody.collapse_sigma_km=0")
    nis = [r["nis"] for r in read_steps(out).to_pylist() if r["kind"] == "update"][-3:]
    v = read_manifest(out)["summary"]["verdict"]
    assert sorted(nis)[1] > 1e3
    assert v["kind"] == "diverged" and v["reason"] == (
        f"measurements far outside the predicted spread: median NIS {sorted(nis)[1]:.3g} over the last 3 updates > 1000")


def test_a_consistent_truthless_run_is_not_diverged_by_the_nis_rule(obs_file, tmp_path):
    out = tmp_path / "run"
    _cli_run(obs_file, out, "filter.n_particles=300", "iod.n_particles=300", "custody.diverged_nis=1e3")
    nis = [r["nis"] for r in read_steps(out).to_pylist() if r["kind"] == "update"][-3:]
    assert sorted(nis)[1] < 1e3 and read_manifest(out)["summary"]["verdict"]["kind"] == "no-truth"


def test_a_truthless_run_stores_its_measurement_consistency_in_the_manifest(obs_file, tmp_path):
    out = tmp_path / "run"
    _cli_run(obs_file, out, "filter.n_particles=300", "iod.n_particles=300")
    s = read_manifest(out)["summary"]
    assert s["verdict"]["kind"] == "no-truth" and s["has_truth"] is False
    rows = read_steps(out).to_pylist()
    c, rs = s["consistency"], residual_summary(rows)
    assert c == pytest.approx(consistency_summary(rows))
    assert (c["nis_mean"], c["nis_lower"], c["nis_upper"], c["nis_updates"]) == pytest.approx(
        (rs.nis_test.mean, rs.nis_test.lower, rs.nis_test.upper, rs.nis_test.n))
    assert c["share_outside_95"] == pytest.approx(rs.share_outside_95)
    assert c["max_abs_residual_arcsec"] == pytest.approx(rs.max_abs_residual_arcsec)
    assert c["nis_dof_total"] == 2 * c["nis_updates"]          # azimuth and elevation at each update


def test_a_study_report_reads_each_runs_consistency_from_its_manifest(observed_study):
    import json

    from cistrack.evaluation.consistency import chi2_ppf
    from cistrack.studies.report import report_study

    study, out = observed_study("observed", "{ name = \"pgm\", n_particles = 300, n_components = 2 }", "[1, 2]")
    cons = []
    for i, d in enumerate(sorted((out / "runs").iterdir())):   # mark the manifests: the report must use them
        man = json.loads((d / "manifest.json").read_text())
        man["summary"]["consistency"]["nis_mean"] = 3.0 + i
        (d / "manifest.json").write_text(json.dumps(man))
        cons.append(man["summary"]["consistency"])
    row = report_study(study, out_dir=out)["rows"][0]
    k = sum(c["nis_updates"] for c in cons)
    dof = sum(c["nis_dof_total"] for c in cons)
    assert row["mean_nis"] == pytest.approx(sum(c["nis_mean"] * c["nis_updates"] for c in cons) / k)
    assert (row["nis_lo"], row["nis_hi"]) == pytest.approx((chi2_ppf(0.025, dof) / k, chi2_ppf(0.975, dof) / k))
    assert row["nis_updates"] == k
    with open(out / "report" / "summary.csv") as fh:
        assert "custody" not in fh.readline()


def test_a_truthless_study_flags_its_diverged_runs_with_the_reason_and_never_says_custody(observed_study):
    from cistrack.studies.report import report_study

    study, out = observed_study("observed-sir", "{ name = \"sir\", n_particles = 300 }", "[1]")
    rep = report_study(study, out_dir=out)
    (run,) = list((out / "runs").iterdir())
    v = read_manifest(run)["summary"]["verdict"]
    assert v["kind"] == "diverged"
    line = f"- {run.name} (sir with noisy-range IOD on quick): diverged: {v['reason']}"
    md = (out / "report" / "summary.md").read_text()
    flat = " ".join(rep["text"].split())  # the terminal report wraps at 120 columns
    assert " ".join(line.split()) in flat and line in md and "## Diverged and failed runs" in md
    assert rep["rows"][0]["verdicts"] == "0/1"                         # no-truth / diverged
    for text in (rep["text"], md, *(p.read_text() for p in (out / "report").glob("*.csv"))):
        assert "custody" not in text.lower()
