"""One site's night with one gross outlier: no burn is searched on an arc this short (a burn's three
parameters fit the outlier as readily as a maneuver: it had taken a 912 +- 626 m/s burn between two
exposures 12 minutes apart and predicted an Earth impact 5 hours later), the fit is reported not
clean, and its warning says the least squares converged."""
from __future__ import annotations

import json

import pytest

from cistrack.cli.main import main

ROWS = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
nrho|CCD|568|2026-04-29T07:30:14.099192Z|191.55705821097963|-4.891664142452307|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T07:42:20.275941Z|191.6274610602796|-4.94059104986468|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T07:55:00.136433Z|191.70062859951547|-4.9923504014232294|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:26:49.246598Z|192.86585846920763|-5.874674533860282|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:34:22.810826Z|192.91050728583393|-5.906780528388479|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:42:27.313984Z|193.03132738612708|-5.959593893098624|0.706|0.706|Gaia3
"""


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("night")
    (d / "night.psv").write_text(ROWS)
    code = main(["fit", str(d / "night.psv"), "--out", str(d / "fit")])
    return code, json.loads((d / "fit" / "fit.json").read_text())


def test_no_burn_is_searched_on_one_night_and_the_fit_is_not_clean(fitted):
    code, record = fitted
    assert code == 3 and not record["converged"] and not record.get("maneuvers")
    assert any("cannot tell a burn from outliers" in m and "no burn was searched" in m for m in record["messages"])


def test_its_warning_says_the_least_squares_converged_but_the_fit_is_not_clean(tmp_path, capsys):
    (tmp_path / "night.psv").write_text(ROWS)
    assert main(["fit", str(tmp_path / "night.psv"), "--out", str(tmp_path / "fit")]) == 3
    out = " ".join(capsys.readouterr().out.split())
    assert "warning: the least squares converged, but the fit is not a clean one" in out
    assert "did not converge" not in out and "impact" not in out


def test_a_fit_whose_least_squares_did_not_converge_never_says_it_converged(tmp_path, capsys):
    """Probe M8: a fit that had not converged (here: its weighted RMS 49 is over fit.max_rms = 10)
    and was not clean had been reported "the least squares converged, but the fit is not a clean one"."""
    (tmp_path / "night.psv").write_text(ROWS)
    assert main(["fit", str(tmp_path / "night.psv"), "--out", str(tmp_path / "fit"), "--set", "fit.max_rms=10"]) == 3
    out = " ".join(capsys.readouterr().out.split())
    assert "warning: the least squares did not converge, and the fit is not a clean one" in out
    assert "the least squares converged" not in out


CLEAN_NIGHT = "\n".join(ROWS.splitlines()[:-1]) + "\n"  # the same night without its outlier


def test_a_poorly_determined_fit_draws_its_line_of_variations_by_default(tmp_path):
    """One site's night: the linear 1-sigma had been printed alone (on another such night it was 18
    times smaller than the error); the line of variations shows where it stops holding."""
    (tmp_path / "night.psv").write_text(CLEAN_NIGHT)
    assert main(["fit", str(tmp_path / "night.psv"), "--out", str(tmp_path / "fit")]) == 0
    record = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert record["settings"]["lov"] == "auto" and record["line_of_variations"]["points"] >= 13
    assert (tmp_path / "fit" / "lov.csv").is_file()
    assert not record["line_of_variations"]["linear"]
    assert main(["export", str(tmp_path / "fit"), "--format", "oem", "--quiet"]) == 0
    head = (tmp_path / "fit" / "estimate.oem").read_text().splitlines()[:4]
    assert any("WARNING: the fit's line of variations bends away from the linear covariance" in line
               and "widened to hold every orbit along the line" in line for line in head)


def test_predict_warns_when_the_fits_bent_line_cannot_be_read(tmp_path, capsys):
    """Without lov.csv predict cannot widen its ellipses to hold the line: it says they understate."""
    (tmp_path / "night.psv").write_text(CLEAN_NIGHT)
    assert main(["fit", str(tmp_path / "night.psv"), "--out", str(tmp_path / "fit"), "--quiet"]) == 0
    (tmp_path / "fit" / "lov.csv").unlink()
    assert main(["predict", str(tmp_path / "fit"), "--site", "568", "--start", "2026-04-30T09:00:00Z",
                 "--stop", "2026-04-30T10:00:00Z"]) == 0
    out = capsys.readouterr().out
    assert "warning: the fit's line of variations bends away from its covariance: the 3-sigma ellipses " \
           "understate where to look" in out
