"""ct.run(out=...) keeps the results of other runs as `cistrack run --out` does (issue 50): another
scenario's or settings' results are refused unless overwrite=True, the same run again replaces its
own, and the folder is locked while the run writes."""
from __future__ import annotations

import pytest

import cistrack as ct
from cistrack.errors import CistrackError, ConfigError
from cistrack.results.dir_lock import run_lock

SHORT = {"duration_days": 1.2}


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
