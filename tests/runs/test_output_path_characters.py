"""An --out holding a control character (a newline, a tab, an escape) is refused before anything
is made: the system takes it, but every message and record naming the results would show it broken
(a newline in --out had been taken, each line naming the run split in two)."""
from __future__ import annotations

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.results.output_paths import check_output_dir


@pytest.mark.parametrize("name", ["two\nlines", "a\ttab", "esc\x1b[31mred", "del\x7f"])
def test_an_out_with_a_control_character_is_refused_and_nothing_is_made(tmp_path, name):
    with pytest.raises(ConfigError, match=r"--out .*: the path holds a control character .* give a name without one"):
        check_output_dir(tmp_path / name, "--out")
    assert list(tmp_path.iterdir()) == []


def test_cistrack_run_with_a_newline_in_out_exits_with_a_usage_error(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "r\nx"), "--quiet"]) == 2
    assert "control character ('\\n' at position" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_an_out_with_spaces_and_unicode_is_made(tmp_path):
    assert check_output_dir(tmp_path / "a run – été", "--out").is_dir()


def test_an_export_file_with_a_control_character_is_refused(tmp_path):
    from cistrack.results.earlier_run import check_export_path
    with pytest.raises(ConfigError, match=r"--out .*control character \('\\r' at position"):
        check_export_path(tmp_path / "orbit\r.oem", tmp_path / "run")


def test_cistrack_predict_with_a_newline_in_its_prefix_is_refused(tmp_path, capsys):
    assert main(["predict", str(tmp_path), "--site", "568", "--out", str(tmp_path / "sky\nx")]) == 2
    assert "control character ('\\n' at position" in capsys.readouterr().err
