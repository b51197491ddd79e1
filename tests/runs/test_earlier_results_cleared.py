"""A run that starts in an earlier results directory removes the files that described the earlier
run or fit (its default exports, a fit's record and residuals), so an export or a check never mixes
the new run with the old one's files."""
from __future__ import annotations

import json

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"


def test_a_run_again_in_its_directory_leaves_no_export_of_the_earlier_run(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "quick", "--out", str(out), "--quiet", "--set", "duration_days=2"]) == 0
    assert main(["export", str(out), "--format", "oem"]) == 0
    assert (out / "estimate.oem").is_file()
    assert main(["run", "quick", "--out", str(out), "--quiet", "--set", "duration_days=1.5", "--overwrite"]) == 0
    assert not (out / "estimate.oem").exists()
    assert main(["export", str(out), "--format", "oem"]) == 0
    assert "2026-01-02T12:00" in (out / "estimate.oem").read_text()


def test_a_run_in_an_earlier_fit_directory_removes_the_fit_so_export_writes_the_run(tmp_path):
    out = tmp_path / "fit"
    assert main(["fit", str(DATA / "observations.psv"), "--out", str(out), "--quiet",
                 "--set", "iod.n_particles=1000", "--set", "filter.n_particles=1000"]) == 0
    assert (out / "fit.json").is_file() and (out / "residuals.csv").is_file()
    assert list(out.glob("residuals-*.png"))
    assert main(["run", "quick", "--out", str(out), "--quiet", "--set", "duration_days=2", "--overwrite"]) == 0
    assert not (out / "fit.json").exists() and not (out / "residuals.csv").exists()
    assert not list(out.glob("residuals-*.png")) and not list(out.glob("residuals-*.svg"))
    assert main(["export", str(out), "--format", "oem"]) == 0
    run_id = json.loads((out / "manifest.json").read_text())["run_id"]
    assert f"OBJECT_ID = {run_id}" in (out / "estimate.oem").read_text()


def test_export_quiet_prints_nothing_and_writes_the_file(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "quick", "--out", str(out), "--quiet", "--set", "duration_days=2"]) == 0
    capsys.readouterr()
    assert main(["export", str(out), "--format", "oem", "--quiet"]) == 0
    assert capsys.readouterr().out == "" and (out / "estimate.oem").is_file()
