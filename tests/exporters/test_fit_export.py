"""`cistrack export` of a `cistrack fit` directory: the fitted orbit on a regular grid over the
arc, optionally predicted beyond it, read back by the independent `oem` package. One fit of the
shipped example (1,000 particles in the IOD and filter) serves every test."""
from __future__ import annotations

import csv
import json
import shutil

import numpy as np
import pytest

from cistrack import units
from cistrack.cli.main import main
from cistrack.errors import CistrackError
from cistrack.fitting.fit_export import GRID_MINUTES, export_fit
from cistrack.fitting.from_observations import fit_files
from cistrack.scenario.loading import builtin_scenario_path
from cistrack.units import TU_S
from cistrack.plugin.registry import default_registry
from cistrack.runs.export import scenario_of

DATA = builtin_scenario_path("real-data").parent / "real_data"


@pytest.fixture(scope="module")
def fit_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("fit") / "fit"
    [one] = fit_files([DATA / "observations.psv"], out=out,
                      settings=["iod.n_particles=1000", "filter.n_particles=1000"])
    assert one.ok
    return out


def _read(path):
    oem = pytest.importorskip("oem")
    return oem.OrbitEphemerisMessage.open(str(path)).segments[0]


def test_oem_names_the_object_by_its_designation(fit_dir, tmp_path):
    seg = _read(export_fit(fit_dir, "oem", tmp_path / "a.oem"))
    assert seg.metadata["OBJECT_NAME"] == "cis0001" and seg.metadata["OBJECT_ID"] == "cis0001"


def test_oem_has_interpolation_keywords_and_utc(fit_dir, tmp_path):
    seg = _read(export_fit(fit_dir, "oem", tmp_path / "a.oem"))
    assert seg.metadata["INTERPOLATION"] == "LAGRANGE" and int(seg.metadata["INTERPOLATION_DEGREE"]) == 7
    assert seg.metadata["TIME_SYSTEM"] == "UTC" and seg.metadata["REF_FRAME"] == "GCRF"


def test_oem_states_lie_on_a_regular_grid_covering_the_arc(fit_dir, tmp_path):
    seg = _read(export_fit(fit_dir, "oem", tmp_path / "a.oem"))
    rows = list(seg.states)
    dt = np.array([(s.epoch - rows[0].epoch).to_value("s") for s in rows])
    np.testing.assert_allclose(np.diff(dt), GRID_MINUTES * 60.0, atol=1e-5)
    arc = json.loads((fit_dir / "fit.json").read_text())["arc"]
    span = (arc["last_tu"] - arc["first_tu"]) * TU_S
    assert dt[-1] >= span - 60.0 and dt[-1] <= span + GRID_MINUTES * 60.0 + 60.0
    assert len(list(seg.covariances)) == len(rows)


def test_predict_extends_the_grid_by_the_days_asked_with_growing_covariance(fit_dir, tmp_path):
    arc_only = list(_read(export_fit(fit_dir, "oem", tmp_path / "a.oem")).states)
    seg = _read(export_fit(fit_dir, "oem", tmp_path / "p.oem", predict_days=2.0))
    rows = list(seg.states)
    assert len(rows) == len(arc_only) + int(2 * 1440 / GRID_MINUTES)
    covs = [c.matrix for c in seg.covariances]
    sig_end = np.sqrt(np.trace(np.asarray(covs[-1])[:3, :3]))
    sig_arc = np.sqrt(np.trace(np.asarray(covs[len(arc_only) - 1])[:3, :3]))
    assert sig_end > sig_arc
    assert "predicted beyond the last observation" in (tmp_path / "p.oem").read_text()


def test_the_predicted_states_are_said_to_start_after_the_last_observation_itself(fit_dir, tmp_path):
    """The COMMENT had named the arc's last grid state (up to 10 minutes after the last observation,
    itself predicted) as where the prediction starts."""
    import json

    last = json.loads((fit_dir / "fit.json").read_text())["arc"]["last_utc"][:19]
    text = (export_fit(fit_dir, "oem", tmp_path / "p.oem", predict_days=0.0001)).read_text()
    comments = " ".join(line.removeprefix("COMMENT ") for line in text.splitlines() if line.startswith("COMMENT"))
    assert f"states after {last}Z are predicted beyond the last observation (made at that time)" in comments
    assert "in whole 10-minute steps" in comments


def test_cli_export_of_a_fit_directory_writes_the_fitted_orbit(fit_dir, tmp_path, capsys):
    d = tmp_path / "copy"
    shutil.copytree(fit_dir, d)
    assert main(["export", str(d), "--format", "oem"]) == 0
    text = (d / "estimate.oem").read_text()
    assert "least-squares" in text and "OBJECT_NAME = cis0001" in text


@pytest.mark.parametrize("name", ["residuals-711.png", "residuals-809.svg", "residuals.csv", "fit.json"])
def test_an_export_over_the_fits_own_results_is_refused(fit_dir, capsys, name):
    before = (fit_dir / name).read_bytes()
    assert main(["export", str(fit_dir), "--out", str(fit_dir / name), "--overwrite"]) == 2
    assert "is one of the results of" in capsys.readouterr().err and (fit_dir / name).read_bytes() == before


@pytest.mark.parametrize("format, suffix", [("OEM", ".oem"), ("Opm", ".opm")])
def test_format_names_are_taken_in_either_case(fit_dir, tmp_path, capsys, format, suffix):
    assert main(["export", str(fit_dir), "--format", format, "--out", str(tmp_path / f"u{suffix}")]) == 0
    assert (tmp_path / f"u{suffix}").read_text().startswith(f"CCSDS_{format.upper()}_VERS")


@pytest.mark.parametrize("option", [["--predict", "3"], ["--covariance", "linear"]])
def test_an_option_the_opm_does_not_use_is_refused_naming_both(fit_dir, tmp_path, capsys, option):
    assert main(["export", str(fit_dir), "--format", "opm", *option, "--out", str(tmp_path / "o.opm")]) == 2
    err = capsys.readouterr().err
    assert f"{option[0]} {option[1]}" in err and "--format opm" in err and "takes no " + option[0] in err
    assert not (tmp_path / "o.opm").exists()


def test_the_opm_says_its_covariance_is_the_fits_own_at_the_epoch(fit_dir, tmp_path):
    from cistrack.plugins.exporters.opm import read_opm

    unscented = export_fit(fit_dir, "opm", tmp_path / "u.opm")
    linear = export_fit(fit_dir, "opm", tmp_path / "l.opm", covariance="linear")
    np.testing.assert_array_equal(read_opm(unscented)["covariance"], read_opm(linear)["covariance"])
    for path in (unscented, linear):
        text = path.read_text()
        assert "COMMENT covariance of the fit at its epoch, not propagated" in text
        assert "propagated by the unscented" not in text and "propagated linearly" not in text
        assert "COMMENT least-squares state and covariance at the fit epoch" in text and "filter's belief" not in text


def test_an_opm_with_a_prediction_span_is_refused_in_python_too(fit_dir, tmp_path):
    with pytest.raises(CistrackError, match="predict_days=3.0: format='opm' writes the one state at the fit epoch"):
        export_fit(fit_dir, "opm", tmp_path / "o.opm", predict_days=3.0)


def test_a_fit_that_did_not_converge_is_refused_unless_forced(fit_dir, tmp_path):
    d = tmp_path / "bad"
    shutil.copytree(fit_dir, d)
    rec = json.loads((d / "fit.json").read_text())
    rec["converged"] = False
    (d / "fit.json").write_text(json.dumps(rec))
    with pytest.raises(CistrackError, match="did not converge.*pass force=True"):
        export_fit(d, "oem")
    path = export_fit(d, "oem", force=True)
    assert "COMMENT WARNING: exported with --force" in path.read_text()


def test_predict_on_a_run_that_is_not_a_fit_is_refused_naming_the_option(tmp_path, capsys):
    (tmp_path / "scenario.toml").write_text("")
    assert main(["export", str(tmp_path), "--predict", "1"]) == 2
    assert "--predict" in capsys.readouterr().err


def test_a_negative_prediction_span_is_refused(fit_dir, tmp_path):
    with pytest.raises(CistrackError, match="predict_days=-1.0: must be a number of days from 0"):
        export_fit(fit_dir, "oem", tmp_path / "n.oem", predict_days=-1.0)


def test_the_covariance_is_carried_by_the_unscented_transform_unless_linear_is_asked(fit_dir, tmp_path, capsys):
    d = tmp_path / "copy"
    shutil.copytree(fit_dir, d)
    assert main(["export", str(d), "--format", "oem"]) == 0
    assert "COMMENT covariance propagated by the unscented transform" in (d / "estimate.oem").read_text()
    assert main(["export", str(d), "--format", "oem", "--covariance", "linear", "--out", str(d / "lin.oem")]) == 0
    unscented = [np.asarray(c.matrix) for c in _read(d / "estimate.oem").covariances]
    linear = [np.asarray(c.matrix) for c in _read(d / "lin.oem").covariances]
    assert "COMMENT covariance propagated linearly" in (d / "lin.oem").read_text()
    # the shipped arc stays far from the Moon: the two agree there to a few percent per element sigma
    for u, v in zip(unscented, linear):
        np.testing.assert_allclose(np.sqrt(np.diag(u)), np.sqrt(np.diag(v)), rtol=0.05)


def test_an_unknown_covariance_method_is_refused_naming_the_option(fit_dir, tmp_path):
    with pytest.raises(CistrackError, match="covariance='quadratic': must be one of unscented, linear"):
        export_fit(fit_dir, "oem", tmp_path / "q.oem", covariance="quadratic")


def test_covariance_on_a_run_that_is_not_a_fit_is_refused_naming_the_option(tmp_path, capsys):
    (tmp_path / "scenario.toml").write_text("")
    assert main(["export", str(tmp_path), "--covariance", "linear"]) == 2
    assert "--covariance" in capsys.readouterr().err


def test_covariances_kept_linear_are_counted_and_dated_in_a_warning(fit_dir, tmp_path):
    d = tmp_path / "into-the-earth"
    shutil.copytree(fit_dir, d)
    rec = json.loads((d / "fit.json").read_text())
    # a rank-one covariance along the line to the Earth's centre: one sigma point (state + sqrt(6)
    # times the square root of the covariance, which the export scales by the noise scale) starts
    # at the Earth's centre, so every covariance falls back to the linear map
    reg = default_registry()
    earth = scenario_of(d, reg).build("dynamics", reg).primary("Earth").position_at(rec["epoch_tu"])
    u = np.zeros(6)
    u[:3] = (earth - np.asarray(rec["state"])[:3]) / np.sqrt(6.0) / max(1.0, rec["noise_scale"])
    rec["covariance"] = np.outer(u, u).tolist()
    (d / "fit.json").write_text(json.dumps(rec))
    text = export_fit(d, "oem").read_text()
    n = len(list(_read(d / "estimate.oem").states))
    assert f"COMMENT WARNING: {n} of {n} covariances, between " in text
    assert "are propagated linearly" in text


def test_a_forced_export_of_a_fit_from_many_sites_keeps_every_line_within_254_characters(fit_dir, tmp_path):
    d = tmp_path / "many-sites"
    shutil.copytree(fit_dir, d)
    rec = json.loads((d / "fit.json").read_text())
    rec["converged"] = False
    rec["arc"]["sites"] = [f"S{k:02d}" for k in range(60)]
    (d / "fit.json").write_text(json.dumps(rec))
    lines = export_fit(d, "oem", force=True).read_text().splitlines()
    assert max(map(len, lines)) <= 254 and len(list(_read(d / "estimate.oem").states)) > 1
    assert any(line.startswith("COMMENT WARNING: exported with --force") for line in lines)


def test_a_designation_too_long_for_the_object_name_line_is_refused_naming_the_keyword(fit_dir, tmp_path):
    d = tmp_path / "long-name"
    shutil.copytree(fit_dir, d)
    rec = json.loads((d / "fit.json").read_text())
    rec["designation"] = "x" * 300
    (d / "fit.json").write_text(json.dumps(rec))
    with pytest.raises(CistrackError, match="OBJECT_NAME 'xxx.*' has 300 characters; .* at most 254"):
        export_fit(d, "oem")
    assert not (d / "estimate.oem").exists()


def test_a_prediction_does_not_silently_replace_the_fits_default_export(fit_dir, tmp_path, capsys):
    d = tmp_path / "copy"
    shutil.copytree(fit_dir, d)
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 0
    arc_only = (d / "estimate.oem").read_text()
    assert main(["export", str(d), "--format", "oem", "--predict", "1", "--quiet"]) == 2
    assert "estimate.oem: already holds a different export" in capsys.readouterr().err
    assert (d / "estimate.oem").read_text() == arc_only
    assert main(["export", str(d), "--format", "oem", "--predict", "1", "--overwrite", "--quiet"]) == 0
    assert "predicted beyond the last observation" in (d / "estimate.oem").read_text()


def test_the_command_line_names_its_own_options_in_an_exports_refusal(fit_dir, tmp_path, capsys):
    (tmp_path / "taken.oem").write_text("")
    assert main(["export", str(fit_dir), "--out", str(tmp_path / "taken.oem")]) == 2
    err = capsys.readouterr().err
    assert f"--out {tmp_path / 'taken.oem'}: already exists" in err and "add --overwrite" in err


def test_python_names_its_keywords_when_the_path_exists(fit_dir, tmp_path):
    (tmp_path / "taken.oem").write_text("")
    with pytest.raises(CistrackError, match=r"path='.*taken.oem': already exists; give another file, or pass "
                                            r"overwrite=True"):
        export_fit(fit_dir, "oem", tmp_path / "taken.oem")


def _burned(fit_dir, d):
    """A copy of ``fit_dir`` whose fit.json says a burn (0.05-day sigma) halfway through its arc; its time, days."""
    shutil.copytree(fit_dir, d)
    rec = json.loads((d / "fit.json").read_text())
    t_burn = 0.5 * (rec["arc"]["first_tu"] + rec["arc"]["last_tu"]) * TU_S / 86400.0
    rec["maneuvers"] = [{"t_days": t_burn + 0.1, "t_burn_days": t_burn, "t_burn_sigma_days": 0.05,
                         "t_burn_utc": units.format_utc(units.tu_to_utc(units.parse_utc(rec["scenario_epoch_utc"]),
                                                                         t_burn * 86400.0 / TU_S)),
                         "delta_v_ms": 0.3, "delta_v_sigma_ms": 0.03,
                         "delta_v_vector_ms": [0.3, 0.0, 0.0], "delta_v_covariance_ms2": np.diag([9e-4] * 3).tolist()}]
    (d / "fit.json").write_text(json.dumps(rec))
    return rec, t_burn


def test_a_fit_with_a_burn_exports_the_orbit_flown_after_it_only(fit_dir, tmp_path):
    """Before its last burn the object flew another orbit than the fitted one: the states start
    3 sigma of the burn's time after it, and a COMMENT says why."""
    d = tmp_path / "burned"
    rec, t_burn = _burned(fit_dir, d)
    text = export_fit(d, "oem", tmp_path / "b.oem").read_text()
    rows = list(_read(tmp_path / "b.oem").states)
    whole = list(_read(export_fit(fit_dir, "oem", tmp_path / "a.oem")).states)
    first_days = (rows[0].epoch - whole[0].epoch).to_value("s") / 86400.0 + rec["arc"]["first_tu"] * TU_S / 86400.0
    assert t_burn + 0.15 <= first_days + 1e-6 <= t_burn + 0.15 + GRID_MINUTES / 1440.0
    assert rows[-1].epoch == whole[-1].epoch and len(rows) < len(whole)
    assert "the fit found 1 impulsive burn(s) (fit.json maneuvers); the states start at" in " ".join(text.split())


def test_a_prediction_of_a_fit_with_a_burn_starts_after_it(fit_dir, tmp_path, capsys):
    """predict had given the post-burn orbit before the burn, with a 0.7-arcsec ellipse 44 sigma from
    the object's own observation there; the times before the burn + 3 sigma are left out, and a
    span wholly before it is refused naming --start."""
    from cistrack import units
    from cistrack.cli.main import main

    d = tmp_path / "burned"
    rec, t_burn = _burned(fit_dir, d)
    epoch = units.parse_utc(rec["scenario_epoch_utc"])
    at = lambda days: units.format_utc(units.tu_to_utc(epoch, float(units.days_to_tu(days))))[:19] + "Z"  # noqa: E731
    common = ["predict", str(d), "--site", "568", "--step", "60", "--out", str(tmp_path / "sky"), "--overwrite"]
    assert main(common + ["--start", at(t_burn - 0.2), "--stop", at(t_burn + 0.3)]) == 0
    assert "prediction times before" in capsys.readouterr().out
    with open(tmp_path / "sky.csv") as fh:
        first = next(csv.DictReader(fh))["utc"]
    assert units.parse_utc(first) >= units.parse_utc(at(t_burn + 0.15))
    assert main(common + ["--start", at(t_burn - 0.3), "--stop", at(t_burn - 0.1)]) == 2
    assert "--start/--stop: every prediction time is before" in capsys.readouterr().err


def test_predicts_notes_fit_within_120_columns_on_a_terminal(fit_dir, tmp_path, capsys, monkeypatch):
    """A note of predict had been one 206-character line on a 120-column terminal."""
    import sys

    from cistrack import units
    from cistrack.cli.main import main

    d = tmp_path / "burned"
    rec, t_burn = _burned(fit_dir, d)
    epoch = units.parse_utc(rec["scenario_epoch_utc"])
    at = lambda days: units.format_utc(units.tu_to_utc(epoch, float(units.days_to_tu(days))))[:19] + "Z"  # noqa: E731
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    assert main(["predict", str(d), "--site", "568", "--step", "60", "--out", str(tmp_path / "sky"), "--start",
                 at(t_burn - 0.2), "--stop", at(t_burn + 0.3)]) == 0
    out = capsys.readouterr().out
    assert "prediction times before" in " ".join(out.split())
    assert max(len(line) for line in out.splitlines()) <= 120


def test_exports_notes_fit_within_120_columns_on_a_terminal(fit_dir, tmp_path, capsys, monkeypatch):
    """export's notes past the fit's horizon had been single lines of 258 and 280 characters."""
    import sys

    from cistrack.cli.main import main

    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    assert main(["export", str(fit_dir), "--format", "oem", "--predict", "30", "--out", str(tmp_path / "e.oem")]) == 0
    out = capsys.readouterr().out
    assert "note: " in out and max(len(line) for line in out.splitlines()) <= 120


def test_a_warning_fits_within_120_columns_on_a_terminal(capsys, monkeypatch):
    """A warning (the kernel cache's, lov.csv's) had been one line of up to 297 characters."""
    import sys

    from cistrack.cli.main import show_warning

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    show_warning(UserWarning("cistrack: " + "a long reason " * 20), UserWarning, "x.py", 1)
    err = capsys.readouterr().err
    assert err.startswith("cistrack: warning: a long reason") and max(len(line) for line in err.splitlines()) <= 120
