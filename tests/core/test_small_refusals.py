"""Small inputs that used to give a vague or misleading answer: each now says what is wrong."""
from __future__ import annotations

import os

import pytest

import cistrack as ct
from cistrack.cli.main import main
from cistrack.errors import ConfigError


def test_an_out_that_is_a_dangling_link_is_named_as_one(tmp_path, capsys):
    link = tmp_path / "dangling"
    os.symlink(tmp_path / "missing" / "x", link)
    assert main(["run", "quick", "--out", str(link), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "a link to" in err and "which does not exist" in err


@pytest.mark.parametrize("scenario, words", [("", "empty name"), (".", "a directory, not a scenario file")])
def test_an_empty_or_directory_scenario_is_named(scenario, words):
    with pytest.raises(ConfigError, match=words):
        ct.load_scenario(scenario)


def test_read_run_of_a_file_says_it_is_a_file(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ConfigError, match=r"not a run's results folder \(a file\)"):
        ct.read_run(tmp_path / "afile")


def test_init_prints_a_command_a_shell_can_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["init", "x y;z"]) == 0
    assert "cistrack run 'x y;z.toml'" in capsys.readouterr().out


def test_an_export_named_for_the_other_message_is_refused(tmp_path, capsys):
    assert main(["export", str(tmp_path), "--format", "opm", "--out", str(tmp_path / "x.oem")]) == 2
    assert "named for OEM, but --format opm writes OPM" in capsys.readouterr().err


def test_an_export_named_for_observations_is_refused(tmp_path, capsys):
    assert main(["export", str(tmp_path), "--format", "oem", "--out", str(tmp_path / "x.psv")]) == 2
    assert "a .psv name is for ADES observations, not a CCSDS OEM; name it" in capsys.readouterr().err
    assert not (tmp_path / "x.psv").exists()


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "r"
    assert main(["run", "quick", "--set", "duration_days=1.2", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.mark.parametrize("name", ["manifest.json", "steps.parquet", "scenario.toml"])
def test_an_export_over_the_runs_own_results_is_refused(quick_run, capsys, name):
    before = (quick_run / name).read_bytes()
    assert main(["export", str(quick_run), "--out", str(quick_run / name), "--overwrite"]) == 2
    assert "is one of the results of" in capsys.readouterr().err and (quick_run / name).read_bytes() == before


def test_a_recording_path_that_is_a_directory_is_refused_before_the_run(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "r"), "--rerun", str(tmp_path / "d") + "/", "--quiet"]) == 2
    assert "a directory; give the recording's file name" in capsys.readouterr().err and not (tmp_path / "r").exists()


@pytest.mark.parametrize("argv", [["run", "quick", "--rerun", ""], ["study", "run", "quick-comparison", "--dask", ""]])
def test_an_empty_option_value_is_refused(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and "is empty" in capsys.readouterr().err


def test_read_run_of_a_truncated_manifest_names_the_file(quick_run, tmp_path):
    import shutil

    shutil.copytree(quick_run, tmp_path / "r")
    (tmp_path / "r" / "manifest.json").write_text((quick_run / "manifest.json").read_text()[:100])
    with pytest.raises(ConfigError, match="manifest.json: cannot be read"):
        ct.read_run(tmp_path / "r")


def test_a_run_with_stderr_closed_finishes(tmp_path):
    import subprocess
    import sys

    code = ("import sys; from cistrack.cli.main import console_main; "
            f"sys.argv = ['cistrack', 'run', 'quick', '--set', 'duration_days=1.2', '--out', {str(tmp_path / 'r')!r}]; "
            "console_main()")
    proc = subprocess.run(["bash", "-c", f'"{sys.executable}" -c "{code}" 2>&-'], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout
    assert (tmp_path / "r" / "steps.parquet").is_file()


def test_a_refused_recording_path_leaves_no_results_directory_behind(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "r"), "--rerun", str(tmp_path / "nodir" / "x.rrd"),
                 "--quiet"]) == 2
    assert "cannot be written" in capsys.readouterr().err and not (tmp_path / "r").exists()
