"""A results folder's ``scenario.toml`` records the seed actually run (``--seed``, or a study's
seed), so that running that file again reproduces the run: into a new folder it gives identical
estimates, and into its own folder it is the same run, not one refused as another seed (probe H4)."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from cistrack.cli.main import main
from cistrack.results.store import read_manifest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SMALL_SET = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
             "--set", "iod.n_particles=300", "--quiet"]


@pytest.fixture(scope="module")
def seed5(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("runs") / "seed5"
    assert main(["run", "quick", "--seed", "5", "--out", str(d), *SMALL_SET]) == 0
    return d


def _estimates(d: Path) -> list:
    """The estimates table's rows, NaN written as None (NaN != NaN), for an exact comparison."""
    rows = pq.read_table(d / "estimates.parquet").to_pylist()
    return [{k: None if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()} for r in rows]


def test_a_run_with_seed_records_that_seed_in_its_scenario_toml(seed5):
    assert tomllib.loads((seed5 / "scenario.toml").read_text())["seed"] == 5 == read_manifest(seed5)["seed"]


def test_running_a_results_folders_scenario_toml_into_a_new_folder_gives_identical_estimates(seed5, tmp_path):
    again = tmp_path / "again"
    assert main(["run", str(seed5 / "scenario.toml"), "--out", str(again), "--quiet"]) == 0
    assert read_manifest(again)["seed"] == 5
    assert _estimates(again) == _estimates(seed5)


def test_running_a_results_folders_scenario_toml_into_its_own_folder_is_the_same_run(seed5, tmp_path, capsys):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(seed5, copy)
    assert main(["run", str(copy / "scenario.toml"), "--out", str(copy), "--quiet"]) == 0, capsys.readouterr().err
    assert _estimates(copy) == _estimates(seed5)


def test_a_study_runs_scenario_toml_records_the_studys_seed(tmp_path):
    from study_files import write_study

    study = write_study(tmp_path, seeds="[7]")
    assert main(["study", "run", str(study), "--out", str(tmp_path / "s"), "--workers", "1"]) == 0
    (run,) = (tmp_path / "s" / "runs").iterdir()
    assert tomllib.loads((run / "scenario.toml").read_text())["seed"] == 7 == read_manifest(run)["seed"]


def test_a_run_into_a_folder_with_an_older_scenario_json_leaves_only_its_scenario_toml(seed5, tmp_path):
    import json
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(seed5, copy)
    (copy / "scenario.json").write_text(json.dumps(tomllib.loads((copy / "scenario.toml").read_text())))
    assert main(["run", str(copy / "scenario.toml"), "--out", str(copy), "--quiet"]) == 0
    assert (copy / "scenario.toml").is_file() and not (copy / "scenario.json").exists()
