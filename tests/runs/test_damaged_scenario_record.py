"""A results folder whose scenario.toml is damaged (hand-edited, truncated) is refused naming the
file by export and predict: they had printed tomllib's TOMLDecodeError traceback."""
from __future__ import annotations

import shutil

import pytest

import cistrack as ct
from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.scenario.loading import recorded_scenario


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    d = tmp_path_factory.mktemp("run") / "r"
    ct.run("quick", settings={"duration_days": 1.2}, out=d)
    return d


def test_a_damaged_record_is_a_config_error_naming_the_file(tmp_path):
    p = tmp_path / "scenario.toml"
    p.write_text("junk = = [\n")
    with pytest.raises(ConfigError, match="scenario.toml: the results folder's record of its scenario is damaged"):
        recorded_scenario(p)


@pytest.mark.parametrize("text", ["junk = = [\n", "\udcff"])
def test_export_of_a_run_with_a_damaged_record_says_so(finished, tmp_path, capsys, text):
    d = tmp_path / "r"
    shutil.copytree(finished, d)
    (d / "scenario.toml").write_bytes(text.encode("utf-8", "surrogateescape"))
    assert main(["export", str(d), "--out", str(tmp_path / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "scenario.toml" in err
