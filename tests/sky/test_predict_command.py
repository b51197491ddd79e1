"""`cistrack predict`: refusals name the option; end to end on a fitted example (slow)."""
import csv

import pytest

from cistrack.cli.main import main


@pytest.mark.parametrize("argv, words", [
    (["predict", "{d}", "--site", "XYZ"], "--site XYZ"),
    (["predict", "{d}/nothing", "--site", "568"], "no such directory"),
    (["predict", "{d}", "--site", "568"], "scenario.toml"),
])
def test_refusals_name_what_is_wrong(tmp_path, capsys, argv, words):
    assert main([a.format(d=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


@pytest.mark.parametrize("option, value", [("--step", "0"), ("--step", "x"), ("--start", "tomorrow")])
def test_bad_option_values_are_refused_by_the_parser(tmp_path, capsys, option, value):
    with pytest.raises(SystemExit) as exc:
        main(["predict", str(tmp_path), "--site", "568", option, value])
    assert exc.value.code == 2 and option in capsys.readouterr().err


@pytest.mark.slow
def test_predict_prints_writes_csv_and_plot_for_a_fit(tmp_path, capsys):
    from cistrack.fitting.from_observations import fit_files
    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    [one] = fit_files([obs], out=tmp_path / "fit")
    assert one.ok
    capsys.readouterr()
    d = str(tmp_path / "fit")
    assert main(["predict", d, "--site", "568", "--start", "2026-03-07T06:00:00Z", "--stop", "2026-03-07T12:00:00Z",
                 "--step", "60"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert all(len(line) <= 120 for line in out if not line.startswith("wrote")) and out[0].startswith("UTC")
    assert len([line for line in out if line.startswith("2026-03-07T")]) == 7
    rows = list(csv.DictReader(open(tmp_path / "fit" / "sky-568.csv")))
    assert len(rows) == 7 and float(rows[0]["semi_major_3sigma_arcsec"]) > 0
    assert (tmp_path / "fit" / "sky-568.png").stat().st_size > 10_000
    assert main(["predict", d, "--site", "568", "--start", "2026-03-08T00:00:00Z", "--stop", "2026-03-07T00:00:00Z"]) == 2
    assert "--stop" in capsys.readouterr().err
    (tmp_path / "taken.csv").mkdir()  # the table's path is a folder: the write fails
    assert main(["predict", d, "--site", "568", "--out", str(tmp_path / "taken")]) == 2
    err = capsys.readouterr().err
    assert "cannot write" in err and "taken.csv" in err and "Traceback" not in err


def test_a_cr3bp_run_is_refused_naming_the_dynamics(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "q"), "--quiet"]) == 0
    assert main(["predict", str(tmp_path / "q"), "--site", "809"]) == 2
    assert "real Earth-Moon frame" in capsys.readouterr().err


@pytest.mark.slow
def test_predict_takes_a_runs_last_filter_estimate(tmp_path, capsys):
    assert main(["run", "real-data", "--out", str(tmp_path / "r"), "--quiet"]) == 0
    assert main(["predict", str(tmp_path / "r"), "--site", "809", "--start", "2026-03-07T00:00:00Z", "--stop",
                 "2026-03-07T06:00:00Z", "--step", "120"]) == 0
    captured = capsys.readouterr()
    assert "filter estimate at step" in captured.err
    assert len([line for line in captured.out.splitlines() if line.startswith("2026-03-07T")]) == 4
