"""`cistrack fit` end to end on the shipped example (observations.psv, two sites, 65 RA/Dec over
4.6 days): the files it writes, what it prints, and its refusals. Real components throughout;
the IOD and the filter run with 1,000 particles to keep the run short (~6 s of CPU)."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
FAST = ["--set", "iod.n_particles=1000", "--set", "filter.n_particles=1000"]
LOV = ["--set", "fit.lov=1"]  # the line of variations, -1 to 1 sigma


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """(results directory, exit status, stdout) of one `cistrack fit` of the shipped ADES file."""
    out = tmp_path_factory.mktemp("fit") / "fit"
    mp = pytest.MonkeyPatch()
    import io
    import sys
    buf = io.StringIO()
    mp.setattr(sys, "stdout", buf)
    try:
        rc = main(["fit", str(DATA / "observations.psv"), "--out", str(out), *FAST, *LOV])
    finally:
        mp.undo()
    return out, rc, buf.getvalue()


def test_the_line_of_variations_is_written_every_half_sigma(fitted):
    rows = list(csv.DictReader((fitted[0] / "lov.csv").read_text().splitlines()))
    assert [float(r["sigma"]) for r in rows] == [-1.0, -0.5, 0.0, 0.5, 1.0]


def test_on_the_shipped_arc_the_line_of_variations_is_straight(fitted):
    """A 4.6-day arc from two sites: the chi-square rises as sigma^2 along the line and the line
    stays on the covariance's axis, so the covariance describes the solutions."""
    rows = list(csv.DictReader((fitted[0] / "lov.csv").read_text().splitlines()))
    for r in rows:
        assert float(r["delta_chi2"]) == pytest.approx(float(r["sigma"]) ** 2, abs=0.02)
    rec = json.loads((fitted[0] / "fit.json").read_text())["line_of_variations"]
    assert rec["linear"] is True and rec["points"] == 5 and rec["max_departure_sigma"] < 0.05


def test_summary_reports_the_line_of_variations(fitted):
    assert "line of variations -1 to 1 sigma (5 points, lov.csv)" in fitted[2]


def test_fit_converges_and_exits_zero(fitted):
    out, rc, _ = fitted
    assert rc == 0
    assert json.loads((out / "fit.json").read_text())["converged"] is True


def test_fit_json_holds_state_covariance_epoch_and_statistics(fitted):
    rec = json.loads((fitted[0] / "fit.json").read_text())
    assert len(rec["state_km"]) == 6 and np.asarray(rec["covariance_km"]).shape == (6, 6)
    assert rec["epoch_utc"] == rec["arc"]["last_utc"]          # the default epoch: the last observation
    assert rec["designation"] == "cis0001"
    assert rec["n_used"] + rec["n_rejected"] == rec["arc"]["n_observations"] == 65
    assert 0.8 < rec["noise_scale"] < 1.25 and rec["chi2"] > 0 and rec["condition_number"] > 1
    assert set(rec["arc"]["sites"]) == {"711", "809"}


def test_fit_recovers_the_truth_within_its_covariance_at_the_fit_epoch(fitted):
    """The truth of the shipped example (truth.csv) lies inside the fitted covariance."""
    from cistrack import units
    from cistrack.fitting.fit_export import _scenario
    from cistrack.plugin.registry import default_registry

    out = fitted[0]
    rec = json.loads((out / "fit.json").read_text())
    scen = _scenario(out, default_registry())
    rows = [r for r in csv.reader(ln for ln in (DATA / "truth.csv").read_text().splitlines()
                                  if not ln.startswith("#"))][1:]
    t_truth = (units.parse_utc(rows[0][0]) - scen.epoch).total_seconds() / units.TU_S
    x0 = units.state_from_km(np.array([float(v) for v in rows[0][1:]]))
    truth = scen.build("dynamics").propagate(x0[None], t_truth, np.array([rec["epoch_tu"]])).states[0, 0]
    e = truth - np.asarray(rec["state"])
    assert float(e @ np.linalg.solve(np.asarray(rec["covariance"]), e)) < 16.8


def test_residuals_csv_has_one_row_per_observation_in_arcsec_on_the_sky(fitted):
    with (fitted[0] / "residuals.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 65
    assert list(rows[0]) == ["utc", "site", "ra_cos_dec_arcsec", "dec_arcsec", "norm_ra_cos_dec", "norm_dec",
                             "chi2", "rejected"]
    rms = np.sqrt(np.mean([float(r["dec_arcsec"]) ** 2 for r in rows]))
    assert 0.7 < rms < 1.3                                         # the example's noise: 1 arcsec
    assert {r["site"] for r in rows} == {"711", "809"} and {r["rejected"] for r in rows} <= {"true", "false"}


def test_a_residual_plot_per_site_in_png_and_svg(fitted):
    names = {p.name for p in fitted[0].iterdir()}
    assert {"residuals-711.png", "residuals-711.svg", "residuals-809.png", "residuals-809.svg"} <= names
    assert (fitted[0] / "residuals-711.png").read_bytes()[:4] == b"\x89PNG"


def test_the_filter_run_files_are_there_too(fitted):
    names = {p.name for p in fitted[0].iterdir()}
    assert {"manifest.json", "steps.parquet", "estimates.parquet", "scenario.toml", "observations.psv"} <= names


def test_summary_prints_rms_chi2_noise_rejections_and_sigmas(fitted):
    text = fitted[2]
    assert "weighted RMS" in text and "chi-square" in text
    assert "assumed noise" in text and "estimated" in text and "noise scale" in text
    assert "rejected" in text and "1-sigma at the fit epoch" in text
    assert "weights: observations.psv" in text


def test_unknown_fit_setting_is_refused_naming_the_key(tmp_path, capsys):
    rc = main(["fit", str(DATA / "observations.psv"), "--out", str(tmp_path / "x"), "--set", "fit.rejekt_sigma=4"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "fit.rejekt_sigma" in err and "reject_sigma" in err
    assert not (tmp_path / "x").exists()


def test_a_wrong_scenario_setting_is_refused_before_anything_runs(tmp_path, capsys):
    rc = main(["fit", str(DATA / "observations.psv"), "--out", str(tmp_path / "x"), "--set", "filter.n_partcles=5"])
    assert rc == 2
    assert "n_partcles" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_missing_file_is_refused_naming_it(tmp_path, capsys):
    rc = main(["fit", str(tmp_path / "none.psv")])
    assert rc == 2
    assert "none.psv" in capsys.readouterr().err


def test_an_export_predicted_past_the_impact_says_where_it_ends(fitted, capsys, tmp_path):
    """The shipped orbit hits the Moon 10.5 days after its last observation: a 30-day prediction
    says so on the terminal and in the file, not only the span asked."""
    oem = tmp_path / "p.oem"
    assert main(["export", str(fitted[0]), "--format", "oem", "--predict", "30", "--out", str(oem)]) == 0
    said = "the predicted states end at the Moon's surface (impact at 2026-03-17T"
    assert f"note: {said}" in capsys.readouterr().out
    assert f"COMMENT WARNING: {said}" in oem.read_text()


def test_fit_json_gives_the_largest_hidden_burn_of_each_gap_between_sessions(fitted):
    """Five sessions, four gaps; the summary names the last one's."""
    rec = json.loads((fitted[0] / "fit.json").read_text())["burn_sensitivity"]
    gaps = rec["gaps"]
    assert rec["sigmas"] == 3.0 and len(gaps) == 4
    assert all(g["start_utc"] < g["t_worst_utc"] < g["end_utc"] for g in gaps)
    assert all(0.0 < g["largest_hidden_ms"] < 100.0 for g in gaps)
    assert all(abs(np.linalg.norm(g["direction_synodic"]) - 1.0) < 1e-9 for g in gaps)
    assert (f"maneuvers: a burn of {gaps[-1]['largest_hidden_ms']:.0f} m/s between {gaps[-1]['start_utc'][:16]} and "
            f"{gaps[-1]['end_utc'][:16]} (the last gap between sessions), at its worst time and direction, would not "
            "show") in " ".join(fitted[2].split())
