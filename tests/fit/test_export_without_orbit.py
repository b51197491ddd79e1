"""A fit that made no orbit (one lone tracklet: UNDETERMINED) has nothing to export, and the refusal
does not suggest --force, which cannot help (it had, and --force was then refused too)."""
from __future__ import annotations

from cistrack.cli.main import main

from .test_lov_solutions import NIGHT

ONE_TRACKLET = "\n".join(NIGHT.splitlines()[:7]) + "\n"  # the header and the first 5 exposures, 29 minutes


def test_an_undetermined_fit_has_nothing_to_export_and_force_is_not_suggested(tmp_path, capsys):
    (tmp_path / "t.psv").write_text(ONE_TRACKLET)
    assert main(["fit", str(tmp_path / "t.psv"), "--out", str(tmp_path / "fit"), "--quiet"]) == 3
    capsys.readouterr()
    for extra in ([], ["--force"]):
        assert main(["export", str(tmp_path / "fit"), "--format", "oem", *extra]) == 2
        err = " ".join(capsys.readouterr().err.split())
        assert "nothing to export: it has no fitted orbit" in err and "--force" not in err
