"""Hostile input, round 4: each case was a traceback, a silent acceptance or a hang of the command
line (or of a component behind it) and is now refused by name. Every command goes through the real
entry point ``cistrack.cli.main`` in a temporary working directory."""
from __future__ import annotations

import json
import os
import shutil
import stat
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError, MeasurementError
from cistrack.results.atomic_files import write_text_atomic
from cistrack.runs.observation_files import read_observations
from cistrack.studies.study_file import load_study

REAL_DATA = Path(__file__).resolve().parents[1] / "core" / "scenarios" / "real_data"
EPOCH = "2026-03-01T00:00:00Z"
QUICK = ["run", "quick", "--set", "duration_days=1.5", "--set", "iod.n_particles=300",
         "--set", "filter.n_particles=300", "--quiet"]


def _refused(argv: list[str], capsys) -> str:
    """Run ``cistrack argv``; assert exit status 2 and no traceback; return stderr."""
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse's refusal of an option value
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("probe4") / "run"
    assert main(QUICK + ["--out", str(d)]) == 0
    return d


# --- files that are not regular files are never replaced -------------------------------------

def test_an_atomic_write_onto_a_fifo_is_refused_and_leaves_the_fifo(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="not a regular file"):
        write_text_atomic(fifo, "data")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_export_overwrite_onto_a_fifo_is_refused_by_name(run_dir, tmp_path, capsys):
    fifo = tmp_path / "pipe.oem"
    os.mkfifo(fifo)
    err = _refused(["export", str(run_dir), "--out", str(fifo), "--overwrite", "--quiet"], capsys)
    assert f"--out {fifo}" in err and "not a regular file" in err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


# --- run folders whose manifest is not a JSON object -------------------------------------------

def test_export_of_a_run_whose_manifest_is_a_list_is_refused_naming_the_manifest(run_dir, tmp_path, capsys):
    broken = tmp_path / "broken"
    shutil.copytree(run_dir, broken)
    (broken / "manifest.json").write_text(json.dumps([1, 2]))
    err = _refused(["export", str(broken), "--out", str(tmp_path / "x.oem"), "--quiet"], capsys)
    assert "manifest.json" in err and "not a cistrack manifest" in err


# --- export --step ----------------------------------------------------------------------------

def test_export_step_with_a_format_that_writes_every_step_is_refused(run_dir, tmp_path, capsys):
    err = _refused(["export", str(run_dir), "--format", "oem", "--step", "2", "--out", str(tmp_path / "x.oem")],
                   capsys)
    assert "--step 2" in err and "--format oem" in err


def test_export_step_with_opm_still_writes_that_step(run_dir, tmp_path):
    out = tmp_path / "x.opm"
    assert main(["export", str(run_dir), "--format", "opm", "--step", "2", "--out", str(out), "--quiet"]) == 0
    assert "at step 2" in out.read_text()


# --- empty path options and counts ------------------------------------------------------------

@pytest.mark.parametrize("argv", [QUICK + ["--out", ""], ["fit", "obs.psv", "--out", " "],
                                  ["predict", "somewhere", "--site", "568", "--out", ""],
                                  ["study", "run", "quick-comparison", "--out", ""]],
                         ids=["run", "fit", "predict", "study"])
def test_an_empty_out_is_refused_rather_than_replaced_by_the_default(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    err = _refused(argv, capsys)
    assert "--out" in err and "is empty" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", ["0", "-1"])
def test_run_max_points_below_one_is_refused(value, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    err = _refused(QUICK + ["--max-points", value], capsys)
    assert "--max-points" in err and ">= 1" in err


# --- cistrack predict -------------------------------------------------------------------------

@pytest.mark.parametrize("option", ["--start", "--stop"])
@pytest.mark.parametrize("when", ["0001-01-01T00:00:00Z", "9999-12-31T00:00:00Z"])
def test_predict_times_outside_the_ephemeris_years_are_refused(option, when, tmp_path, capsys):
    err = _refused(["predict", str(tmp_path), "--site", "568", option, when], capsys)
    assert option in err and "1900 to 2052" in err


def test_predict_out_in_a_missing_folder_is_refused_before_any_work(tmp_path, capsys):
    err = _refused(["predict", str(tmp_path), "--site", "568", "--out", str(tmp_path / "no" / "x")], capsys)
    assert "--out" in err and "does not exist" in err


# --- cistrack init ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["", ".", "..", " ", "sub/..", ".toml"])
def test_init_refuses_a_name_that_names_no_file(name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    err = _refused(["init", "--", name], capsys)
    assert "NAME" in err and "my-scenario" in err
    assert list(tmp_path.iterdir()) == []


# --- cistrack view ----------------------------------------------------------------------------

@pytest.mark.parametrize("content", [b"", b"hello, not a recording"], ids=["empty", "text"])
def test_view_refuses_a_file_that_is_not_a_recording_without_starting_a_viewer(content, tmp_path, capsys):
    f = tmp_path / "x.rrd"
    f.write_bytes(content)
    err = _refused(["view", str(f)], capsys)
    assert str(f) in err and "not a rerun recording" in err


# --- readers ----------------------------------------------------------------------------------

def test_an_unknown_reader_parameter_is_a_config_error_naming_it():
    with pytest.raises(ConfigError, match="reader 'ades-psv': unknown parameter 'bogus'; its parameters: "
                                          "sigma_arcsec"):
        read_observations(REAL_DATA / "observations.psv", EPOCH, bogus=1)


def test_fit_with_an_unknown_reader_parameter_is_refused(tmp_path, capsys):
    err = _refused(["fit", str(REAL_DATA / "observations.psv"), "--set", "measurements.reader.bogus=1",
                    "--out", str(tmp_path / "f"), "--quiet"], capsys)
    assert "unknown parameter 'bogus'" in err


@pytest.mark.parametrize("year", ["0001", "9999"])
def test_an_ades_time_outside_the_supported_years_names_line_and_field(year, tmp_path):
    lines = (REAL_DATA / "observations.psv").read_text().splitlines()
    f = tmp_path / "obs.psv"
    f.write_text("\n".join(lines[:2] + [x.replace("2026-03", f"{year}-03") for x in lines[2:]]) + "\n")
    with pytest.raises(MeasurementError, match=r"line 3, field obsTime: time .* outside the years cistrack "
                                               r"supports \(1800 to 2199\)"):
        read_observations(f, EPOCH)


def test_a_csv_time_in_year_one_is_refused_by_line(tmp_path):
    f = tmp_path / "obs.csv"
    f.write_text("time_utc,azimuth_deg,elevation_deg\n0001-01-01T00:00:00Z,10,20\n0001-01-01T01:00:00Z,11,21\n")
    with pytest.raises(MeasurementError, match="line 2: time_utc '0001-01-01T00:00:00Z': .*1800 to 2199"):
        read_observations(f, EPOCH)


# --- study files ------------------------------------------------------------------------------

@pytest.mark.parametrize("line", ["filters = []", "iod = []", 'filters = "pgm"'])
def test_a_study_with_an_empty_or_unlisted_variant_key_is_refused(line, tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(f'name = "s"\nscenarios = ["quick"]\n{line}\nseeds = [1]\n')
    key = line.split()[0]
    with pytest.raises(ConfigError, match=f"key '{key}'.*leave '{key}' out"):
        load_study(f)


# --- [measurements] file ----------------------------------------------------------------------

def test_a_measurements_file_that_is_a_device_is_named_as_such_not_as_missing(tmp_path, capsys):
    err = _refused(QUICK + ["--set", "measurements.file=/dev/null", "--out", str(tmp_path / "r")], capsys)
    assert "[measurements] file = /dev/null: is not a regular file" in err


def test_a_fit_of_observations_the_ephemeris_cannot_model_names_the_file_not_the_settings(tmp_path, capsys):
    from cistrack.cli.main import main
    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    text = (builtin_scenario_path("real-data").parent / "real_data" / "observations.psv").read_text()
    old = tmp_path / "y1850.psv"
    old.write_text(text.replace("|2026-", "|1850-"))
    assert main(["fit", str(old), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(old) in err and "run from 1850-03-01" in err and "which the fit cannot model" in err


def test_a_refused_fit_quotes_the_first_observations_date_not_the_epoch_before_it(tmp_path, capsys):
    """A file whose first observation is 1900-01-01T00:00 had been said to 'start 1899-12-31', the
    fit's epoch 30 minutes before it (probe I4). The whole arc is moved to January 1900: one
    observation alone outside the ephemeris' years is set aside, not refused
    (tests/fit/test_arcs_outside_ephemeris.py)."""
    from cistrack.cli.main import main
    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    text = (builtin_scenario_path("real-data").parent / "real_data" / "observations.psv").read_text()
    lines = text.replace("|2026-03-0", "|1900-01-0").splitlines()
    row = next(i for i, line in enumerate(lines) if "|1900-" in line)
    f = lines[row].split("|")
    f[next(j for j, c in enumerate(f) if c.strip().startswith("1900-"))] = "1900-01-01T00:00:00Z"
    lines[row] = "|".join(f)
    typo = tmp_path / "y1900.psv"
    typo.write_text("\n".join(lines) + "\n")
    assert main(["fit", str(typo), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "observations of" in err and "run from 1900-01-01T00:00:00" in err and "start 1899" not in err
