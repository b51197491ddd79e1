"""A study's results directory stands for the study: `cistrack study report DIR` reports the runs
it holds, with the seeds and --set values they were run with."""
from __future__ import annotations

import concurrent.futures as cf
import json

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.studies.study import load_study, run_study
from cistrack.studies.report import report_study

SETTINGS = ["filter.n_particles=250"]


def test_report_of_a_study_directory_equals_the_report_of_its_file_with_the_same_seeds_and_settings(
        tiny_study, tmp_path):
    out = tmp_path / "s"
    run_study(tiny_study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False,
              settings=SETTINGS, first_seed=5, n_seeds=2)
    by_dir = report_study(out)
    by_file = report_study(tiny_study, out_dir=out, settings=SETTINGS, first_seed=5, n_seeds=2)
    assert by_dir["rows"][0]["runs"] == 2
    assert by_dir["rows"] == by_file["rows"]


def test_a_study_run_on_its_directory_finds_every_run_done(tiny_study, tmp_path):
    out = tmp_path / "s"
    run_study(tiny_study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False,
              settings=SETTINGS, first_seed=5, n_seeds=2)
    res = run_study(out, executor=cf.ThreadPoolExecutor(1), progress=False)
    assert (res["completed"], res["skipped"], res["failed"]) == (0, 2, 0)


def test_report_of_a_directory_that_holds_no_study_is_refused_naming_it(tmp_path, capsys):
    assert main(["study", "report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert str(tmp_path) in err and "no study.json" in err and "Traceback" not in err


@pytest.mark.parametrize("edit, words", [
    ({"run_seeds": ["1"]}, "key 'run_seeds': seed '1' must be an integer"),
    ({"name": "../../etc"}, "key 'name': '../../etc' contains a path separator"),
    ({"settings": ["duration_days=nan"]}, "(with {record}: key 'settings' = ['duration_days=nan'])"),
    ({"settings": ["garbage"]}, "{record}: key 'settings': --set 'garbage': expected TABLE.KEY=VALUE"),
    ({"settings": "duration_days=2"}, "{record}: key 'settings' = 'duration_days=2': not a list"),
])
def test_a_damaged_value_in_a_study_directorys_record_is_blamed_on_that_record(tiny_study, tmp_path, edit, words):
    """The study file the record names had been blamed for the record's own values."""
    out = tmp_path / "s"
    out.mkdir()
    record = {"source": str(tiny_study), **load_study(tiny_study)[0], "settings": [], "run_seeds": [1]}
    (out / "study.json").write_text(json.dumps({**record, **edit}))
    with pytest.raises(ConfigError) as refused:
        report_study(out)
    text = str(refused.value)
    assert words.format(record=out / "study.json") in text and str(tiny_study) not in text
    if "{record}" not in words:
        assert text.startswith(f"{out / 'study.json'}: ")


@pytest.mark.parametrize("holds, words", [("manifest.json", "the results of a single run (manifest.json)"),
                                          ("fit.json", "a fit's results (fit.json)")])
def test_report_into_a_run_or_fit_folder_says_what_it_holds_as_study_run_does(tiny_study, tmp_path, holds, words,
                                                                               capsys):
    folder = tmp_path / "single"
    folder.mkdir()
    (folder / "manifest.json").write_text("{}")
    (folder / holds).write_text("{}")
    for command in ("report", "run"):
        assert main(["study", command, str(tiny_study), "--out", str(folder)]) == 2
        err = capsys.readouterr().err
        assert f"--out {folder}: holds {words}, not " in err and "Run it first" not in err
