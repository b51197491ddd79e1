"""The Python API: ``import cistrack as ct; ct.run("quick", seed=2)`` runs a scenario as the CLI
does and gives its verdict, summary and per-step table."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import cistrack as ct
from cistrack.api import Run
from cistrack.errors import ConfigError

SMALL = {"duration_days": 2}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory) -> Run:
    return ct.run("quick", seed=2, settings=SMALL, out=tmp_path_factory.mktemp("api") / "r")


def test_run_returns_the_summary_and_one_row_per_step(quick_run):
    assert quick_run.status == "finished"
    assert quick_run.run_id == "quick__pgm__noisy-range__seed2"
    assert len(quick_run.steps) == quick_run.summary.n_steps == len(quick_run.rows)


def test_run_gives_the_same_numbers_as_the_cli(quick_run, tmp_path):
    out = tmp_path / "cli"
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--seed", "2", "--quiet",
                           "--set", "duration_days=2", "--out", str(out)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    cli = ct.read_run(out).steps
    api = quick_run.steps
    for column in ("t_days", "pos_err_km", "nees", "entropy", "sigma_x_km"):
        np.testing.assert_array_equal(api[column].to_numpy(), cli[column].to_numpy())


def test_read_run_gives_back_the_written_run(quick_run):
    again = ct.read_run(quick_run.directory)
    assert again.verdict == quick_run.verdict
    assert again.steps["nees"].equals(quick_run.steps["nees"])


def test_settings_accept_dotted_keys_and_nested_tables():
    a = ct.load_scenario("quick", settings={"filter.n_particles": 700, "duration_days": 2})
    b = ct.load_scenario("quick", settings={"filter": {"n_particles": 700}, "duration_days": 2})
    assert a.components["filter"].params["n_particles"] == b.components["filter"].params["n_particles"] == 700


def test_a_wrong_setting_names_the_table_and_key():
    with pytest.raises(ConfigError, match="n_particles"):
        ct.load_scenario("quick", settings={"filter.n_particles": -5})


def test_read_run_of_a_folder_without_a_run_says_so(tmp_path):
    with pytest.raises(ConfigError, match="manifest"):
        ct.read_run(tmp_path)


def test_importing_cistrack_does_not_import_the_api():
    proc = subprocess.run([sys.executable, "-c", "import sys, cistrack; print('cistrack.api' in sys.modules)"],
                          capture_output=True, text=True, timeout=60)
    assert proc.stdout.strip() == "False"
