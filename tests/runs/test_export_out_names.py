"""An export never writes over another folder's lock or results: 'export A --out B/.fit.lock
--overwrite' had replaced the lock of a fit running in B, and a second fit then ran beside it."""
from __future__ import annotations

import pytest

import cistrack as ct
from cistrack.cli.main import main


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    d = tmp_path_factory.mktemp("run") / "r"
    ct.run("quick", settings={"duration_days": 1.2}, out=d)
    return d


@pytest.mark.parametrize("name", [".fit.lock", ".run.lock", ".fit-started", ".study.lock"])
def test_a_lock_name_is_never_an_export_target(finished, tmp_path, capsys, name):
    target = tmp_path / "other" / name
    target.parent.mkdir()
    target.write_text("")
    assert main(["export", str(finished), "--out", str(target), "--overwrite"]) == 2
    assert "to know who writes there" in capsys.readouterr().err and target.read_text() == ""


def test_another_folders_results_are_no_export_target(finished, tmp_path, capsys):
    other = tmp_path / "fit"
    other.mkdir()
    (other / "fit.json").write_text("{}")
    assert main(["export", str(finished), "--out", str(other / "fit.json"), "--overwrite"]) == 2
    assert f"is one of the results of {other}" in capsys.readouterr().err
    assert (other / "fit.json").read_text() == "{}"


def test_a_plain_file_elsewhere_is_written(finished, tmp_path):
    assert main(["export", str(finished), "--out", str(tmp_path / "orbit.oem")]) == 0


@pytest.mark.parametrize("format, hint", [("", ""), ("oem ", ". Did you mean 'oem'?")])
def test_an_unknown_format_is_refused_by_its_name_before_the_out_name_is_judged_by_it(finished, tmp_path, capsys,
                                                                                    format, hint):
    """The --out name had been blamed: "--out x.oem: named for OEM, but --format oem  writes OEM "."""
    assert main(["export", str(finished), "--format", format, "--out", str(tmp_path / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert f"unknown exporter {format!r}; available: " in err and hint in err and "--out" not in err
