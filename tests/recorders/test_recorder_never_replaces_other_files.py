"""A recording replaces only a recording: ``--overwrite`` (``overwrite=true``) had let
``cistrack run myq.toml --rerun myq.toml --overwrite`` write the recording over the run's own scenario
file, and ``--rerun obs.psv`` over an observation file. A recording's name ends in .rrd (``--rerun -``
had written a file named '-', ``--rerun x.txt`` one that ``cistrack view`` then refused)."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.errors import ParameterError
from cistrack.plugin.registry import default_registry

QUICK = Path(__file__).resolve().parents[2] / "core" / "scenarios" / "quick.toml"


def test_a_path_not_ending_in_rrd_is_refused(tmp_path):
    with pytest.raises(ParameterError, match="must end in .rrd"):
        default_registry().create("recorder", "rerun", path=str(tmp_path / "run.txt"))


def test_overwrite_does_not_replace_a_file_that_is_not_a_recording(tmp_path):
    other = tmp_path / "notes.rrd"
    other.write_text("my notes\n")
    with pytest.raises(ParameterError, match="is not a rerun recording"):
        default_registry().create("recorder", "rerun", path=str(other), overwrite=True)
    assert other.read_text() == "my notes\n"


@pytest.mark.parametrize("content", [b"", b"RRF2\x00\x29\x00\x00"])
def test_overwrite_replaces_a_recording_or_an_empty_file(tmp_path, content):
    old = tmp_path / "old.rrd"
    old.write_bytes(content)
    assert default_registry().create("recorder", "rerun", path=str(old), overwrite=True).path == str(old)


def test_the_run_refuses_its_own_scenario_file_as_the_recording(tmp_path, capsys):
    scenario = tmp_path / "myq.toml"
    shutil.copy(QUICK, scenario)
    before = scenario.read_bytes()
    assert main(["run", str(scenario), "--out", str(tmp_path / "out"), "--rerun", str(scenario), "--overwrite"]) == 2
    assert scenario.read_bytes() == before
    assert "--rerun" in capsys.readouterr().err


def test_the_run_refuses_an_existing_file_that_is_not_a_recording_even_with_overwrite(tmp_path, capsys):
    obs = tmp_path / "obs.rrd"
    obs.write_text("2026-01-01T00:00:00Z|1.0|2.0\n")
    assert main(["run", "quick", "--out", str(tmp_path / "out"), "--rerun", str(obs), "--overwrite"]) == 2
    assert obs.read_text().startswith("2026") and "is not a rerun recording" in capsys.readouterr().err


def test_standard_output_is_not_a_recording_path(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "out"), "--rerun", "-"]) == 2
    assert "standard output is not supported" in capsys.readouterr().err
    assert not (Path.cwd() / "-").exists()
