"""cistrack fit never replaces a run's results or another object's fit without --overwrite."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.fitting.fit_replacing import check_fit_replacing
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

OBSERVATIONS = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("run") / "r"
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--quiet"]) == 0
    return out


def test_a_fit_into_a_runs_folder_is_refused_and_leaves_it_alone(run_dir, capsys):
    before = (run_dir / "manifest.json").read_bytes()
    assert main(["fit", str(OBSERVATIONS), "--out", str(run_dir), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(run_dir) in err and "cistrack run" in err and "--overwrite" in err
    assert (run_dir / "manifest.json").read_bytes() == before and not (run_dir / "fit.json").exists()


def test_another_objects_fit_is_not_replaced(tmp_path):
    (tmp_path / "fit.json").write_text(json.dumps({"designation": "2025-010D"}))
    with pytest.raises(ConfigError, match="another object, '2025-010D'"):
        check_fit_replacing(tmp_path, "C2RLB52", "--out")


def test_an_earlier_fit_of_the_same_object_is_redone(tmp_path):
    (tmp_path / "fit.json").write_text(json.dumps({"designation": "C2RLB52"}))
    assert check_fit_replacing(tmp_path, "C2RLB52", "--out") == ""


def test_overwrite_names_what_it_replaces(run_dir, tmp_path):
    copy = tmp_path / "r"
    shutil.copytree(run_dir, copy)
    assert "cistrack run" in check_fit_replacing(copy, "C2RLB52", "--out", overwrite=True)
