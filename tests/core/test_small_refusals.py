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
