"""cistrack fit never replaces a run's results or another object's fit without --overwrite."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.fitting.fit_replacing import check_fit_replacing
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

OBSERVATIONS = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("run") / "r"
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--quiet"]) == 0
    return out


def test_a_fit_into_a_runs_folder_is_refused_and_leaves_it_alone(run_dir, capsys):
    before = (run_dir / "manifest.json").read_bytes()
    assert main(["fit", str(OBSERVATIONS), "--out", str(run_dir), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(run_dir) in err and "cistrack run" in err and "--overwrite" in err
    assert (run_dir / "manifest.json").read_bytes() == before and not (run_dir / "fit.json").exists()


def test_another_objects_fit_is_not_replaced(tmp_path):
    (tmp_path / "fit.json").write_text(json.dumps({"designation": "2025-010D"}))
    with pytest.raises(ConfigError, match="another object, '2025-010D'"):
        check_fit_replacing(tmp_path, "C2RLB52", "--out")


def test_an_earlier_fit_of_the_same_object_is_redone(tmp_path):
    (tmp_path / "fit.json").write_text(json.dumps({"designation": "C2RLB52"}))
    assert check_fit_replacing(tmp_path, "C2RLB52", "--out") == ""


def test_overwrite_names_what_it_replaces(run_dir, tmp_path):
    copy = tmp_path / "r"
    shutil.copytree(run_dir, copy)
    assert "cistrack run" in check_fit_replacing(copy, "C2RLB52", "--out", overwrite=True)


@pytest.fixture(scope="module")
def fit_over_run(run_dir, tmp_path_factory) -> Path:
    """The run's folder after ``cistrack fit --overwrite`` of the shipped observations into it."""
    out = tmp_path_factory.mktemp("fit") / "r"
    shutil.copytree(run_dir, out)
    assert (out / "residuals.svg").is_file()
    assert main(["fit", str(OBSERVATIONS), "--out", str(out), "--overwrite", "--quiet"]) == 0
    return out


def test_a_fit_with_overwrite_leaves_nothing_of_the_run_it_replaced(fit_over_run):
    assert (fit_over_run / "fit.json").is_file()
    assert not (fit_over_run / "residuals.svg").exists()  # the run's figure, of the other orbit


def test_a_run_with_overwrite_leaves_nothing_of_the_fit_it_replaced(fit_over_run, tmp_path):
    out = tmp_path / "r"
    shutil.copytree(fit_over_run, out)
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--overwrite", "--quiet"]) == 0
    left = sorted(p.name for p in out.iterdir() if p.name.startswith(("observations", "fit", "residuals-", ".fit-")))
    assert left == [] and (out / "residuals.svg").is_file()


def test_a_run_of_a_fits_own_scenario_into_its_folder_is_refused_and_leaves_the_fit(fit_over_run, tmp_path, capsys):
    out = tmp_path / "f"
    shutil.copytree(fit_over_run, out)
    before = (out / "fit.json").read_bytes()
    assert main(["run", str(out / "scenario.toml"), "--out", str(out), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert f"--out {out}: holds the fit of " in err and "A run never replaces a fit's results" in err
    assert (out / "fit.json").read_bytes() == before and (out / "residuals.csv").is_file()


def _one_tracklet_each(path: Path, designations: list[str]) -> Path:
    """An ADES PSV file: the first two observations of the shipped example for each designation
    (one short tracklet each: every fit stops before its filter run and writes its fit.json)."""
    header, *rows = OBSERVATIONS.read_text(encoding="utf-8").splitlines()[:4]
    body = [header, rows[0]] + [name + row[row.index("|"):] for name in designations for row in rows[1:3]]
    path.write_text("\n".join(body) + "\n", encoding="utf-8")
    return path


def test_objects_whose_names_make_the_same_folder_name_each_get_their_own(tmp_path, capsys):
    names = ["2026 AB", "2026/AB", "2026_ab"]
    obs = _one_tracklet_each(tmp_path / "three.psv", names)
    assert main(["fit", str(obs), "--out", str(tmp_path / "out"), "--quiet"]) == 3  # one tracklet each
    folders = sorted((tmp_path / "out").iterdir())
    assert len(folders) == 3
    assert sorted(json.loads((f / "fit.json").read_text())["designation"] for f in folders) == sorted(names)


def test_a_fit_that_stopped_before_its_run_is_redone_in_its_folder(tmp_path, capsys):
    obs = _one_tracklet_each(tmp_path / "one.psv", ["C2RLB52"])
    out = tmp_path / "out"
    assert main(["fit", str(obs), "--out", str(out), "--quiet"]) == 3
    assert not (out / "manifest.json").exists() and (out / "fit.json").is_file()
    capsys.readouterr()
    assert main(["fit", str(obs), "--out", str(out), "--quiet"]) == 3
    assert "not empty" not in capsys.readouterr().err


def test_a_failed_fit_suggests_no_export_and_gives_no_orbit_to_predict_from(tmp_path, capsys):
    obs = _one_tracklet_each(tmp_path / "one.psv", ["C2RLB52"])
    out = tmp_path / "out"
    assert main(["fit", str(obs), "--out", str(out)]) == 3
    assert "next: cistrack export" not in capsys.readouterr().out
    assert main(["predict", str(out), "--site", "809"]) == 2
    assert "no orbit to predict from: it has no fitted orbit" in capsys.readouterr().err


@pytest.mark.parametrize("item", ["truth.dynamics.name=cr3bp", "schedule.name=every"])
def test_settings_of_tables_a_fit_does_not_use_are_refused(tmp_path, capsys, item):
    assert main(["fit", str(OBSERVATIONS), "--out", str(tmp_path / "f"), "--quiet", "--set", item]) == 2
    assert "cistrack fit simulates nothing" in capsys.readouterr().err and not (tmp_path / "f").exists()


def test_a_refit_of_another_arcs_form_does_not_leave_the_earlier_beside_it(tmp_path, capsys):
    out = str(tmp_path / "f")
    assert main(["fit", str(OBSERVATIONS), "--out", out, "--quiet"]) == 0
    assert main(["fit", str(OBSERVATIONS), "--out", out, "--quiet", "--set", "fit.arcs=each"]) == 2
    assert "holds the fit of the whole arc (fit.json) from an earlier fit with another fit.arcs" in capsys.readouterr().err
    assert main(["fit", str(OBSERVATIONS), "--out", out, "--quiet", "--set", "fit.arcs=each", "--overwrite"]) == 0
    assert not (tmp_path / "f" / "fit.json").exists() and not (tmp_path / "f" / "manifest.json").exists()
    assert [p.name for p in (tmp_path / "f").glob("arc-*")] == ["arc-2026-03-01"]
    assert main(["fit", str(OBSERVATIONS), "--out", out, "--quiet"]) == 2
    assert "1 folder(s) of a fit of each arc (arc-2026-03-01)" in capsys.readouterr().err


def test_what_the_sensor_measures_is_not_a_setting_of_a_fit(tmp_path, capsys):
    """The files say it; an RA/Dec file with sensor.measurement=azel had run the IOD twice and then failed."""
    assert main(["fit", str(OBSERVATIONS), "--out", str(tmp_path / "f"), "--quiet", "--set", "sensor.measurement=azel"]) == 2
    assert "--set sensor.measurement='azel': cistrack fit sets what the sensor measures" in capsys.readouterr().err
    assert not (tmp_path / "f").exists()


def test_a_folder_of_several_objects_fits_names_where_one_of_them_goes(tmp_path, capsys):
    """Refitting one object into the --out of a several-object fit had been refused as holding no
    cistrack results, with no way forward."""
    for name in ("fit-a", "fit-b"):
        (tmp_path / "both" / name).mkdir(parents=True)
        (tmp_path / "both" / name / "fit.json").write_text('{"format": "cistrack-fit"}')
    assert main(["fit", str(OBSERVATIONS), "--out", str(tmp_path / "both"), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "it holds the fits of several objects, one folder each: fit-a, fit-b" in err
    assert f"give --out {tmp_path / 'both'}/fit-<designation>" in err


def test_using_the_range_of_observations_that_measure_none_is_refused(tmp_path, capsys):
    assert main(["fit", str(OBSERVATIONS), "--out", str(tmp_path / "f"), "--quiet", "--set", "fit.use_range=true"]) == 2
    assert "measure no range, so there is none to use" in capsys.readouterr().err and not (tmp_path / "f").exists()


@pytest.mark.parametrize("command", [["export", "{d}", "--overwrite"], ["predict", "{d}", "--site", "568"]])
def test_export_and_predict_are_refused_while_a_fit_writes_in_the_folder(fit_over_run, capsys, command):
    from cistrack.results.dir_lock import fit_lock

    with fit_lock(fit_over_run):  # a refit of the folder under way (the lock any 'cistrack fit' there holds)
        assert main([a.format(d=fit_over_run) for a in command]) == 2
    err = capsys.readouterr().err
    assert "a 'cistrack fit'" in err and "is writing its results in this directory" in err
    assert not any(p.name.startswith(("estimate.", "sky-")) for p in fit_over_run.iterdir())


def test_a_run_with_overwrite_keeps_the_users_own_files_in_a_fit_folder(fit_over_run, tmp_path):
    out = tmp_path / "r"
    shutil.copytree(fit_over_run, out)
    (out / "observations-from-telescope.tdm").write_text("mine\n")
    (out / "arc-notes").mkdir()
    shutil.copy(out / "fit.json", out / "arc-notes" / "fit.json")
    (out / "arc-notes" / "mynotes.txt").write_text("mine\n")
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--overwrite", "--quiet"]) == 0
    assert (out / "observations-from-telescope.tdm").read_text() == "mine\n"
    assert (out / "arc-notes" / "mynotes.txt").is_file() and not (out / "observations.psv").exists()


def test_an_export_or_prediction_whose_fit_was_written_again_meanwhile_writes_nothing(fit_over_run, tmp_path):
    """A refit that starts and ends while an export or prediction computes (the lock check at their
    start and end sees no writer) changes fit.json: the file they would write describes the old orbit."""
    from cistrack.results.dir_lock import RunBusy, check_unchanged, results_stamp

    d = tmp_path / "r"
    shutil.copytree(fit_over_run, d)
    stamp = results_stamp(d)
    check_unchanged(d, stamp, "export")  # nothing written meanwhile: no refusal
    record = (d / "fit.json").read_text()
    (d / "fit.json").unlink()
    (d / "fit.json").write_text(record)  # the same text, written again: another file
    with pytest.raises(RunBusy, match="results were written again while the export was made"):
        check_unchanged(d, stamp, "export")


def test_a_fit_of_several_objects_into_a_one_object_fits_folder_is_refused_without_overwrite(tmp_path, capsys):
    """Each object's fit goes to OUT/fit-<designation>: the one-object fit at OUT's top had been left
    beside them (exit 0), and predict OUT had then used its stale orbit."""
    out = tmp_path / "out"
    assert main(["fit", str(_one_tracklet_each(tmp_path / "one.psv", ["C2RLB52"])), "--out", str(out), "--quiet"]) == 3
    before = (out / "fit.json").read_bytes()
    two = _one_tracklet_each(tmp_path / "two.psv", ["A1", "B2"])
    capsys.readouterr()
    assert main(["fit", str(two), "--out", str(out), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert (f"--out {out}: holds the fit of one object (fit.json); this fit of several objects writes a folder for "
            "each (fit-<designation>) and would leave it beside them") in err and "add --overwrite to remove it" in err
    assert (out / "fit.json").read_bytes() == before and not list(out.glob("fit-*"))


def test_a_fit_of_several_objects_with_overwrite_removes_the_one_object_fit_at_the_top(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["fit", str(_one_tracklet_each(tmp_path / "one.psv", ["C2RLB52"])), "--out", str(out), "--quiet"]) == 3
    two = _one_tracklet_each(tmp_path / "two.psv", ["A1", "B2"])
    assert main(["fit", str(two), "--out", str(out), "--quiet", "--overwrite"]) == 3  # one tracklet each
    assert not (out / "fit.json").exists() and not list(out.glob("observations*"))
    assert sorted(p.name for p in out.glob("fit-*")) == ["fit-A1", "fit-B2"]


def test_a_redo_stopped_once_its_new_observations_are_written_leaves_no_earlier_fit_for_export_or_predict(
        fit_over_run, tmp_path, capsys):
    """An interrupted redo had left the earlier fit.json beside the new observations, and export
    and predict used its orbit without a word (probe I2): the redo removes it before it writes them."""
    from cistrack.fitting.observation_input import read_object_observations, write_merged
    from cistrack.plugin.registry import default_registry

    d = tmp_path / "r"
    shutil.copytree(fit_over_run, d)
    registry = default_registry()
    obj = read_object_observations([OBSERVATIONS], registry)[0]
    write_merged(d / "observations", obj.measurements.subset(np.arange(len(obj.measurements)) % 2 == 0),
                 obj.designation, registry)  # the redo's first write; then it is stopped
    assert not (d / "fit.json").exists()
    for command in (["export", str(d), "--out", str(tmp_path / "x.oem")], ["predict", str(d), "--site", "568"]):
        assert main(command) == 2
        assert "did not complete" in capsys.readouterr().err
    assert not (tmp_path / "x.oem").exists()
