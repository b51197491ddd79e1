"""`cistrack predict`: refusals name the option; end to end on a fitted example (slow)."""
import csv

import numpy as np
import pytest

from real_data_fit import fitted_example  # tests/ is on sys.path

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


@pytest.mark.parametrize("option, value", [("--step", "0"), ("--step", "x"), ("--step", "1e15"), ("--start", "tomorrow")])
def test_bad_option_values_are_refused_by_the_parser(tmp_path, capsys, option, value):
    with pytest.raises(SystemExit) as exc:
        main(["predict", str(tmp_path), "--site", "568", option, value])
    assert exc.value.code == 2 and option in capsys.readouterr().err


def test_a_default_stop_beyond_de421_is_named_as_the_default_with_its_time():
    """--start 2052-12-31T12:00Z alone had been refused as '--stop 2053-01-01', an option not given."""
    from types import SimpleNamespace

    from cistrack import units
    from cistrack.cli.predict_command import _times
    from cistrack.errors import ConfigError

    args = SimpleNamespace(run="fit", start=units.parse_utc("2052-12-31T12:00:00Z"), stop=None, step=60.0)
    with pytest.raises(ConfigError) as err:
        _times(args, orbit=None)
    assert str(err.value).startswith("the default --stop (one day after --start) 2053-01-01T12:00Z:")
    assert "give an earlier --start or an explicit --stop" in str(err.value)


@pytest.mark.parametrize("value", ["0.0001", "0.0166"])
def test_a_step_under_the_second_the_times_are_written_to_is_refused(tmp_path, capsys, value):
    """0.0001 minutes had written 10,001 rows under 61 distinct (rounded) time stamps."""
    with pytest.raises(SystemExit) as exc:
        main(["predict", str(tmp_path), "--site", "568", "--step", value])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--step" in err and "at least 0.01667 minutes (1 second" in err


@pytest.mark.parametrize("site, count", [("45,10", 2), ("45,10,0,5", 4)])
def test_coordinates_of_the_wrong_count_are_told_as_coordinates_not_as_an_unknown_code(tmp_path, capsys, site, count):
    from cistrack.cli.predict_command import _site
    from cistrack.errors import ConfigError

    with pytest.raises(ConfigError, match=rf"--site {site}: LAT,LON,HEIGHT_M must be three numbers .* got {count}"):
        _site(site)


def test_two_different_sites_are_refused_rather_than_the_first_dropped(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["predict", str(tmp_path), "--site", "568", "--site", "J04"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--site given twice (568 and J04)" in err and "once per site" in err


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
    (tmp_path / "taken.csv").mkdir()  # the table's path is a folder
    assert main(["predict", d, "--site", "568", "--out", str(tmp_path / "taken")]) == 2
    err = capsys.readouterr().err
    assert "taken.csv already exists" in err and "--overwrite" in err and "Traceback" not in err
    assert main(["predict", d, "--site", "568", "--out", str(tmp_path / "taken"), "--overwrite"]) == 2
    err = capsys.readouterr().err  # asked to replace it, the write fails: said, not a traceback
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


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    return fitted_example(tmp_path_factory)


def _predicted(fitted, tmp_path, capsys, site: str, start: str, stop: str, step: str) -> tuple[str, list[dict]]:
    """(printed text, CSV rows) of a successful ``cistrack predict`` of ``fitted``."""
    assert main(["predict", str(fitted), "--site", site, "--start", start, "--stop", stop, "--step", step,
                 "--out", str(tmp_path / "p")]) == 0
    with open(tmp_path / "p.csv") as fh:
        return capsys.readouterr().out, list(csv.DictReader(fh))


def test_a_window_across_the_impact_is_predicted_up_to_it_and_says_so(fitted, tmp_path, capsys):
    out, rows = _predicted(fitted, tmp_path, capsys, "809", "2026-03-16T20:00:00Z", "2026-03-17T06:00:00Z", "60")
    assert "the orbit hits the Moon at 2026-03-17T00:56" in out and "the 6 prediction times after it" in out
    assert len(rows) == 5


def test_a_time_less_than_30_s_before_the_impact_is_predicted(fitted, tmp_path, capsys):
    # 2026-03-17T00:56:10Z: 17 s before the impact, so its central +-30 s rate difference would cross it
    out, rows = _predicted(fitted, tmp_path, capsys, "568", "2026-03-16T00:56:10Z", "2026-03-18T01:00:00Z", "1440")
    assert "the orbit hits the Moon at 2026-03-17T00:56" in out and "the 1 prediction times after it" in out
    assert [r["utc"] for r in rows] == ["2026-03-16T00:56:10Z", "2026-03-17T00:56:10Z"]


def test_a_window_after_the_impact_is_refused_naming_start(fitted, tmp_path, capsys):
    assert main(["predict", str(fitted), "--site", "809", "--start", "2026-03-18T00:00:00Z",
                 "--out", str(tmp_path / "p")]) == 2
    assert "--start: the orbit hits the Moon at 2026-03-17T00:56" in capsys.readouterr().err


def test_times_far_from_the_fit_say_the_orbit_no_longer_gives_the_sky_position(fitted, tmp_path, capsys):
    assert main(["predict", str(fitted), "--site", "809", "--start", "1990-01-01T00:00:00Z",
                 "--out", str(tmp_path / "p")]) == 0
    assert "3-sigma ellipse is longer than 10 degrees" in capsys.readouterr().out


def _sky_with_major_axes(arcsec: list[float]):
    """A stand-in sky ephemeris whose 1-sigma ellipses have these semi-major axes (arcsec)."""
    from types import SimpleNamespace

    a = np.asarray(arcsec, dtype=float)
    return SimpleNamespace(ellipse=lambda: (a, a / 10.0, np.zeros_like(a)))


def test_an_ellipse_beyond_the_sky_is_told_as_the_whole_sky_with_no_number_of_degrees():
    """Six years before the arc the note had read "longer than 10 degrees (up to 1.55e+06)", with no unit."""
    from cistrack.cli.predict_command import _lost_note

    note = _lost_note(_sky_with_major_axes([1.86e9, 60.0]))
    assert "up to the whole sky: semi-major axes beyond 180 degrees" in note and "e+06" not in note


def test_an_ellipse_within_the_sky_gives_its_length_in_degrees():
    from cistrack.cli.predict_command import _lost_note

    assert "(up to 45 degrees)" in _lost_note(_sky_with_major_axes([15.0 * 3600.0, 60.0]))


def test_the_table_shows_all_sky_for_an_axis_beyond_180_degrees():
    from cistrack.cli.predict_command import _axis_cell

    assert _axis_cell(5.58e9) == "  all sky" and _axis_cell(5.99e3) == " 5.99e+03"


@pytest.mark.parametrize("prefix, replaced", [("residuals", "residuals.csv"), ("residuals-711", "residuals-711.png"),
                                              ("steps/x", "steps/x.csv"), ("fit", None)])
def test_an_out_prefix_over_the_fits_own_results_is_refused(fitted, tmp_path, capsys, prefix, replaced):
    import shutil

    d = tmp_path / "fit"
    shutil.copytree(fitted, d)
    before = {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}
    assert main(["predict", str(d), "--site", "568", "--out", str(d / prefix), "--quiet"]) == (2 if replaced else 0)
    err = capsys.readouterr().err
    if replaced:
        assert f"--out {d / prefix}: {d / replaced}: is one of the results of {d}" in err and "sky-568" in err
    assert {p.name: p.read_bytes() for p in d.iterdir() if p.name in before} == before


def test_an_out_naming_a_pipe_or_device_is_refused_and_nothing_is_written_beside_it(fitted, tmp_path, capsys):
    """Probe I8: `predict --out /dev/null` had written /dev/null.csv and /dev/null.png."""
    import os

    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    assert main(["predict", str(fitted), "--site", "568", "--out", str(pipe), "--quiet"]) == 2
    assert "names a device or pipe, not a file or folder" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]


def test_times_past_the_covariance_horizon_get_the_note_an_export_gives(fitted, tmp_path, capsys):
    """The shipped fit's covariance holds its orbits for 3.75 days past the last observation
    (2026-03-06T12:03Z), its orbits a 1-degree field for 10.5: predicted 5 days on, the ellipses
    understate the spread, and the note says so as the OEM's COMMENT WARNING does."""
    window = ["--start", "2026-03-11T12:00:00Z", "--stop", "2026-03-11T18:00:00Z", "--step", "360"]
    assert main(["predict", str(fitted), "--site", "568", *window, "--out", str(tmp_path / "late")]) == 0
    out = capsys.readouterr().out
    assert "note: the covariances understate the spread of the orbits the fit allows from 3.75 days" in out
    assert "beyond the fit's horizon" not in out
    early = ["--start", "2026-03-07T00:00:00Z", "--stop", "2026-03-07T06:00:00Z", "--step", "360"]
    assert main(["predict", str(fitted), "--site", "568", *early, "--out", str(tmp_path / "early")]) == 0
    assert "understate" not in capsys.readouterr().out


def test_quiet_drops_the_table_but_not_the_notes_on_the_prediction(fitted, tmp_path, capsys):
    """Probe M9: --quiet had dropped the notes too, so that predictions past the covariance horizon
    (or a year before the arc) were written with their ellipses and no caveat."""
    window = ["--start", "2026-03-11T12:00:00Z", "--stop", "2026-03-11T18:00:00Z", "--step", "360"]
    assert main(["predict", str(fitted), "--site", "568", *window, "--out", str(tmp_path / "late"), "--quiet"]) == 0
    captured = capsys.readouterr()
    assert "2026-03-11T" not in captured.out and "wrote" not in captured.out
    assert "note: the covariances understate the spread of the orbits the fit allows from 3.75 days" in captured.err


def test_the_csv_flags_each_time_past_the_covariance_horizon(fitted, tmp_path, capsys):
    """The shipped fit's last observation is 2026-03-06T12:03Z and its covariance holds for 3.75
    days: to 2026-03-10T06:03Z. The file itself carries the caveat, row by row."""
    _, rows = _predicted(fitted, tmp_path, capsys, "568", "2026-03-10T00:00:00Z", "2026-03-10T12:00:00Z", "360")
    assert [(r["utc"], r["beyond_checked_horizon"]) for r in rows] == [
        ("2026-03-10T00:00:00Z", "False"), ("2026-03-10T06:00:00Z", "False"), ("2026-03-10T12:00:00Z", "True")]


def test_a_gap_that_could_hide_a_burn_of_any_size_is_said_beside_the_predictions(fitted, tmp_path, capsys):
    """Probe K8: a fit whose gap hides a burn of any size (burn_sensitivity null: not determined
    there, as before a lone tracklet) had been predicted from with ellipses and no word that they
    assume no burn; the shipped fit's gaps hide at most 25 m/s and get no such note."""
    import json
    import shutil

    window = ["--start", "2026-03-07T00:00:00Z", "--stop", "2026-03-07T06:00:00Z", "--step", "360"]
    assert main(["predict", str(fitted), "--site", "568", *window, "--out", str(tmp_path / "as_fitted")]) == 0
    assert "would not show" not in capsys.readouterr().out
    blind = tmp_path / "blind"
    shutil.copytree(fitted, blind)
    rec = json.loads((blind / "fit.json").read_text())
    rec["burn_sensitivity"]["gaps"][-1]["largest_hidden_ms"] = None
    (blind / "fit.json").write_text(json.dumps(rec))
    assert main(["predict", str(blind), "--site", "568", *window, "--out", str(tmp_path / "blind_p"), "--quiet"]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert ("note: a burn of any size between 2026-03-05T07:46 and 2026-03-06T06:40 would not show in the fit's "
            "observations: these predictions assume none") in err


def test_an_out_prefix_over_another_fits_residual_plot_is_refused_even_with_overwrite(fitted, tmp_path, capsys):
    import shutil

    other = tmp_path / "other"
    shutil.copytree(fitted, other)
    plot = next(other.glob("residuals-*.png"))
    before = plot.read_bytes()
    out = other / plot.stem
    assert main(["predict", str(fitted), "--site", "568", "--out", str(out), "--overwrite", "--quiet"]) == 2
    assert f"is one of the results of {other}" in capsys.readouterr().err
    assert plot.read_bytes() == before and not out.with_suffix(".csv").exists()


def test_a_refit_in_the_directory_removes_the_sky_prediction_of_the_earlier_orbit(fitted, tmp_path, capsys):
    import shutil

    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    d = tmp_path / "fit"
    shutil.copytree(fitted, d)
    assert main(["predict", str(d), "--site", "568", "--quiet"]) == 0
    assert (d / "sky-568.csv").is_file() and (d / "sky-568.png").is_file()
    lines = (builtin_scenario_path("real-data").parent / "real_data" / "observations.psv").read_text().splitlines()
    (tmp_path / "part.psv").write_text("\n".join(lines[:62]) + "\n")     # the first nights only: another orbit
    assert main(["fit", str(tmp_path / "part.psv"), "--out", str(d), "--quiet"]) == 0
    assert not (d / "sky-568.csv").exists() and not (d / "sky-568.png").exists()


def test_a_full_disk_for_the_plot_leaves_neither_file_and_an_earlier_pair_as_it_was(fitted, tmp_path, capsys,
                                                                                     monkeypatch):
    import builtins
    import os

    window = ["predict", str(fitted), "--site", "568", "--out", str(tmp_path / "p"), "--quiet"]
    assert main([*window, "--step", "360"]) == 0
    before = {f.name: f.read_bytes() for f in tmp_path.iterdir()}
    assert sorted(before) == ["p.csv", "p.png"]
    real_open = builtins.open

    def open_on_full_disk(file, mode="r", *args, **kwargs):  # the plot's writes go to /dev/full (ENOSPC)
        if isinstance(file, (str, os.PathLike)) and "w" in mode and "p.png" in os.fspath(file):
            return real_open("/dev/full", mode, *args, **kwargs)
        return real_open(file, mode, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", open_on_full_disk)
    assert main([*window, "--step", "60", "--overwrite"]) == 2
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert f"--out {tmp_path / 'p'}: cannot write {tmp_path / 'p.png'} (No space left on device)" in err
    assert "neither p.csv nor p.png was written" in err and "Traceback" not in err
    assert {f.name: f.read_bytes() for f in tmp_path.iterdir()} == before  # no temporary file left either


def test_a_fit_that_did_not_complete_gives_no_orbit_to_predict_from(fitted, tmp_path, capsys):
    import shutil

    shutil.copytree(fitted, tmp_path / "fit")
    (tmp_path / "fit" / "fit.json").unlink()  # as a fit interrupted after its filter run leaves it
    assert main(["predict", str(tmp_path / "fit"), "--site", "568"]) == 2
    err = capsys.readouterr().err
    assert "no orbit to predict from" in err and "fit did not complete" in err


def test_an_interrupted_run_gives_no_orbit_to_predict_from(tmp_path, capsys):
    import json

    out = tmp_path / "run"
    assert main(["run", "quick", "--set", "duration_days=1.2", "--out", str(out), "--quiet"]) == 0
    man = json.loads((out / "manifest.json").read_text())
    (out / "manifest.json").write_text(json.dumps({**man, "status": "interrupted"}))
    capsys.readouterr()
    assert main(["predict", str(out), "--site", "568"]) == 2
    assert "no orbit to predict from: it was interrupted" in capsys.readouterr().err


def test_a_site_given_by_coordinates_predicts_as_its_mpc_code_does(fitted, tmp_path, capsys):
    from cistrack.astro.sites import observatory

    la_silla = observatory("809")
    given = f"{la_silla.latitude_deg!r},{la_silla.longitude_deg!r},{la_silla.height_m!r}"
    window = ["--start", "2026-03-07T00:00:00Z", "--stop", "2026-03-07T04:00:00Z", "--quiet"]
    assert main(["predict", str(fitted), "--site", "809", "--out", str(tmp_path / "code"), *window]) == 0
    assert main(["predict", str(fitted), f"--site={given}", "--out", str(tmp_path / "given"), *window]) == 0
    by_code = list(csv.DictReader(open(tmp_path / "code.csv")))
    by_place = list(csv.DictReader(open(tmp_path / "given.csv")))
    assert [r["ra_deg"] for r in by_code] == [r["ra_deg"] for r in by_place]
    assert [r["elevation_deg"] for r in by_code] == [r["elevation_deg"] for r in by_place]


@pytest.mark.parametrize("named", ["sky.csv", "sky.png", "sky.CSV"])
def test_an_out_naming_one_of_the_two_files_is_taken_as_their_prefix(fitted, tmp_path, capsys, named):
    window = ["--start", "2026-03-07T00:00:00Z", "--stop", "2026-03-07T02:00:00Z", "--quiet"]
    assert main(["predict", str(fitted), "--site", "809", "--out", str(tmp_path / named), *window]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sky.csv", "sky.png"]  # not sky.csv.csv


def test_a_different_prediction_does_not_replace_the_default_files_unasked(fitted, capsys):
    at = ["predict", str(fitted), "--site", "G96", "--quiet", "--step", "360"]
    assert main(at) == 0
    before = (fitted / "sky-G96.csv").read_bytes()
    assert main(at) == 0                                   # the same prediction again: the same files
    assert main([*at[:-1], "180"]) == 2
    assert "already holds a different prediction" in capsys.readouterr().err
    assert (fitted / "sky-G96.csv").read_bytes() == before
    assert main([*at[:-1], "180", "--overwrite"]) == 0 and (fitted / "sky-G96.csv").read_bytes() != before


def test_a_given_prefix_that_exists_is_replaced_only_with_overwrite(fitted, tmp_path, capsys):
    at = ["predict", str(fitted), "--site", "568", "--quiet", "--step", "360", "--out", str(tmp_path / "q")]
    assert main(at) == 0
    assert main(at) == 2 and "already exists" in capsys.readouterr().err
    assert main([*at, "--overwrite"]) == 0


def _from_the_moon():
    """An orbit 7,700 km from the Moon moving straight away from it: carried back, it meets the Moon."""
    from datetime import datetime, timezone

    from cistrack.fitting.sky_ephemeris import DirectoryOrbit
    from tests.fit.arcs import cr3bp_arc

    dyn = cr3bp_arc().dynamics
    state = np.array([1.0 - dyn.mu + 0.02, 0.0, 0.0, 1.0, 0.0, 0.0])
    return DirectoryOrbit(state, np.eye(6) * 1e-12, 0.0, datetime(2026, 1, 1, tzinfo=timezone.utc), dyn, "x", "fit")


def test_times_before_the_body_the_orbit_came_from_are_left_out_with_a_note():
    from cistrack.cli.predict_command import _until_impact

    times, note = _until_impact(np.array([-0.3, -0.2, -0.01, 0.05]), _from_the_moon())
    assert times.tolist() == [-0.01, 0.05]
    assert note.startswith("note: carried back from its epoch, the orbit meets the Moon at 2025-12-31T") \
        and "the 2 prediction times before it are left out" in note


def test_a_window_wholly_before_that_body_is_refused_naming_start():
    from cistrack.cli.predict_command import _until_impact
    from cistrack.errors import ConfigError

    with pytest.raises(ConfigError, match=r"^--start: carried back from its epoch, the orbit meets the Moon at .*"
                                          r"give a --start after it"):
        _until_impact(np.array([-0.3, -0.2]), _from_the_moon())


def test_a_folder_given_as_the_prefix_gets_the_files_inside_it(fitted, tmp_path):
    (tmp_path / "sky").mkdir()
    for out in (str(tmp_path / "sky") + "/", str(tmp_path / "sky")):
        assert main(["predict", str(fitted), "--site", "568", "--quiet", "--step", "360", "--out", out,
                     "--overwrite"]) == 0
    assert sorted(p.name for p in (tmp_path / "sky").iterdir()) == ["sky-568.csv", "sky-568.png"]
    assert not (tmp_path / "sky.csv").exists()



def test_an_out_folder_holding_another_fits_results_is_refused_naming_it_unless_overwrite(fitted, tmp_path, capsys):
    """Its sky-568 files had been written among the other fit's results, to be taken for its own prediction."""
    import shutil

    other = shutil.copytree(fitted, tmp_path / "other", ignore=shutil.ignore_patterns("sky-*"))
    assert main(["predict", str(fitted), "--site", "568", "--quiet", "--step", "360", "--out", str(other)]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert (f"its folder {other} holds the fit of 'cis0001' (fit.json), not those of {fitted}; the prediction "
            "written there would be taken for one of theirs" in err and "add --overwrite" in err)
    assert not list(other.glob("sky-*"))
    assert main(["predict", str(fitted), "--site", "568", "--quiet", "--step", "360", "--out", str(other),
                 "--overwrite"]) == 0
    assert sorted(p.name for p in other.glob("sky-*")) == ["sky-568.csv", "sky-568.png"]


@pytest.mark.parametrize("reason, advice", [
    ("ENAMETOOLONG", "the name is too long for the file system: give a shorter PREFIX"),
    ("ENOSPC", "the disk or quota is full: give a PREFIX in a folder with room, or free some"),
    ("EACCES", "give a PREFIX in a folder you can write to"),
])
def test_a_prediction_that_cannot_be_written_is_advised_by_the_reason(reason, advice):
    """A name too long had been told to find a folder "you can write to, with room" (probe J8)."""
    import errno

    from cistrack.cli.predict_command import _write_advice

    assert _write_advice(getattr(errno, reason)) == advice
