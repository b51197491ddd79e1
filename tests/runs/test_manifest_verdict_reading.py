"""``cistrack.read_run`` never invents a verdict: a manifest whose summary's verdict is null, or
of a kind no run records, or whose status is missing or unknown, is refused naming the manifest,
and ``cistrack export`` refuses the same manifests: the two readers agree on whether a run
finished (probe H5). Real run of the quick scenario, its manifest edited."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import cistrack as ct
from cistrack.cli.main import main
from cistrack.errors import ConfigError



def _edited(finished: Path, tmp_path: Path, edit) -> Path:
    d = tmp_path / "run"
    shutil.copytree(finished, d, ignore=shutil.ignore_patterns(".run.lock"))
    manifest = json.loads((d / "manifest.json").read_text())
    edit(manifest)
    (d / "manifest.json").write_text(json.dumps(manifest))
    return d


EDITS = {
    "null verdict": (lambda m: m["summary"].__setitem__("verdict", None), "its verdict is null, not a table"),
    "unknown verdict kind": (lambda m: m["summary"]["verdict"].__setitem__("kind", "kept"),
                             "its verdict kind 'kept' is not one a run records"),
    "no status": (lambda m: m.pop("status"), "its status is None, not one a run writes"),
    "integer status": (lambda m: m.__setitem__("status", 7), "its status is 7, not one a run writes"),
    "no summary": (lambda m: m.pop("summary"), "holds no run summary"),
}


@pytest.mark.parametrize("case", list(EDITS))
def test_read_run_refuses_a_manifest_whose_verdict_or_status_no_run_writes(finished_quick_run, tmp_path, case):
    edit, words = EDITS[case]
    d = _edited(finished_quick_run, tmp_path, edit)
    with pytest.raises(ConfigError) as err:
        ct.read_run(d)
    assert str(err.value).startswith(f"{d}/manifest.json: ") and words in str(err.value)


@pytest.mark.parametrize("case", list(EDITS))
def test_export_refuses_the_manifests_read_run_refuses(finished_quick_run, tmp_path, case, capsys):
    d = _edited(finished_quick_run, tmp_path, EDITS[case][0])
    assert main(["export", str(d), "--out", str(tmp_path / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert f"{d}: not exported: " in err and "Traceback" not in err and not (tmp_path / "x.oem").exists()


def test_the_unedited_run_reads_with_its_recorded_verdict(finished_quick_run):
    manifest = json.loads((finished_quick_run / "manifest.json").read_text())
    assert ct.read_run(finished_quick_run).verdict.kind == manifest["summary"]["verdict"]["kind"] != "kept"
