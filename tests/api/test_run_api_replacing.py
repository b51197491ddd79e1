"""ct.run(out=...) keeps the results of other runs as `cistrack run --out` does (issue 50): another
scenario's or settings' results are refused unless overwrite=True, the same run again replaces its
own, and the folder is locked while the run writes."""
from __future__ import annotations

import json

import pytest

import cistrack as ct
from cistrack.errors import CistrackError, ConfigError
from cistrack.results.dir_lock import run_lock
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

SHORT = {"duration_days": 1.2}
OBSERVATIONS = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"


def test_a_run_with_other_settings_is_refused_in_a_folder_holding_results(tmp_path):
    ct.run("quick", settings=SHORT, out=tmp_path / "r")
    with pytest.raises(ConfigError, match="duration_days"):
        ct.run("quick", settings={"duration_days": 1.3}, out=tmp_path / "r")


def test_overwrite_replaces_them(tmp_path):
    ct.run("quick", settings=SHORT, out=tmp_path / "r")
    again = ct.run("quick", settings={"duration_days": 1.3}, out=tmp_path / "r", overwrite=True)
    assert again.summary.status == "finished"


def test_the_same_run_again_replaces_its_own_results(tmp_path):
    first = ct.run("quick", settings=SHORT, out=tmp_path / "r")
    again = ct.run("quick", settings=SHORT, out=tmp_path / "r")
    assert again.summary.final == first.summary.final


def test_a_folder_another_run_is_writing_in_is_refused_at_once(tmp_path):
    d = tmp_path / "r"
    d.mkdir()
    with run_lock(d):
        with pytest.raises(CistrackError, match="another 'cistrack run'"):
            ct.run("quick", settings=SHORT, out=d)


def _results_of_another_run(d):
    """A folder holding another run's results (its manifest and step table), as far as the refusal reads."""
    d.mkdir()
    (d / "manifest.json").write_text(json.dumps({"run_id": "other__ukf__seed9", "versions": {"cistrack": "0.2"},
                                                 "status": "finished", "scenario": "other", "seed": 9,
                                                 "fingerprint": "another"}))
    (d / "steps.parquet").write_bytes(b"")
    return d


def test_the_refusal_from_python_names_the_keywords_not_the_command_line_options(tmp_path):
    d = _results_of_another_run(tmp_path / "r")
    with pytest.raises(ConfigError, match=r"give another out=, remove .*, or pass overwrite=True to replace them"):
        ct.run("quick", settings=SHORT, out=d)


def test_the_refusal_from_python_says_nothing_of_dash_dash_options(tmp_path):
    d = _results_of_another_run(tmp_path / "r")
    with pytest.raises(ConfigError) as refused:
        ct.run("quick", settings=SHORT, out=d)
    assert "--" not in str(refused.value)


def test_a_fit_from_python_into_a_runs_folder_is_refused_naming_the_keywords(tmp_path):
    d = _results_of_another_run(tmp_path / "r")
    with pytest.raises(ConfigError, match=r"^out .*give another out=, remove .*, or pass overwrite=True"):
        ct.fit(OBSERVATIONS, out=d, progress=False)


def test_a_fit_from_python_into_another_objects_fit_is_refused_naming_the_keywords(tmp_path):
    d = tmp_path / "f"
    d.mkdir()
    (d / "fit.json").write_text(json.dumps({"designation": "2025-010D"}))
    with pytest.raises(ConfigError, match=r"another object, '2025-010D'.*pass overwrite=True"):
        ct.fit(OBSERVATIONS, out=d, progress=False)


def test_a_read_run_whose_step_table_is_gone_says_so_by_name(tmp_path):
    """ct.read_run on a folder with its manifest but no steps had raised a bare FileNotFoundError."""
    ct.run("quick", settings=SHORT, out=tmp_path / "r")
    (tmp_path / "r" / "steps.parquet").unlink()
    run = ct.read_run(tmp_path / "r")
    with pytest.raises(ConfigError, match="no results .*step table is gone"):
        run.table()
