"""A study run whose manifest.json is damaged (a JSON list, a summary that is a list, a summary
without its run id) is treated like one whose manifest was cut short: `study report` lists it as
not finished and `study run` runs it again, saying so with the file, never a traceback."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from cistrack.errors import ConfigError
from cistrack.results.store import read_manifest
from cistrack.studies.report import report_study
from cistrack.studies.study import run_study
from study_files import write_study

DAMAGED = {
    "a list": [],
    "a summary that is a list": {"status": "finished", "summary": []},
    "a summary without run_id": {"status": "finished", "summary": {"verdict": 5}},
}


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> tuple[Path, Path]:
    """(the study file, its directory with both runs finished)."""
    d = tmp_path_factory.mktemp("damaged")
    study = write_study(d, seeds="[1, 2]")
    run_study(study, out_dir=d / "out", workers=1)
    return study, d / "out"


def _damaged(finished, tmp_path, content) -> tuple[Path, Path, Path]:
    study, out = finished
    copy = tmp_path / "out"
    shutil.copytree(out, copy)
    run = sorted((copy / "runs").iterdir())[0]
    (run / "manifest.json").write_text(json.dumps(content))
    return study, copy, run


@pytest.mark.parametrize("content", DAMAGED.values(), ids=DAMAGED.keys())
def test_the_report_lists_a_run_with_a_damaged_manifest_as_not_finished(finished, tmp_path, content):
    study, out, run = _damaged(finished, tmp_path, content)
    rep = report_study(study, out_dir=out)
    assert rep["missing"] == 1 and f"not finished: {run.name}" in rep["text"]


@pytest.mark.parametrize("content", DAMAGED.values(), ids=DAMAGED.keys())
def test_study_run_runs_again_a_run_with_a_damaged_manifest_saying_so_by_its_file(finished, tmp_path, content, capsys):
    study, out, run = _damaged(finished, tmp_path, content)
    res = run_study(study, out_dir=out, workers=1, progress=False)
    assert (res["completed"], res["skipped"], res["failed"]) == (1, 1, 0)
    assert read_manifest(run)["summary"]["run_id"] == run.name
    err = " ".join(capsys.readouterr().err.split())  # the notice is wrapped within 120 columns
    assert f"manifest.json is cut short or damaged (it cannot be read back) are run again: {run / 'manifest.json'}" in err
    assert "fingerprint changed" not in err


def test_reading_back_a_run_whose_summary_lacks_its_run_id_names_the_manifest(finished, tmp_path):
    import cistrack

    _, _, run = _damaged(finished, tmp_path, DAMAGED["a summary without run_id"])
    with pytest.raises(ConfigError, match=r"manifest\.json: not a run summary: its 'run_id' is None"):
        cistrack.read_run(run)


def test_the_notice_of_runs_run_again_stays_within_120_columns(capsys):
    from types import SimpleNamespace

    from cistrack.studies.study import _say_rerun

    specs = [SimpleNamespace(run_id=f"example-1-burn[dv=1,resp=inflate]__pgm__noisy-range__seed{k}", out_dir=f"r{k}")
             for k in range(4)]
    _say_rerun(specs, {s.run_id: "gone" for s in specs})
    err = capsys.readouterr().err
    assert "4 run(s) were left 'running'" in err and max(len(line) for line in err.splitlines()) <= 120
