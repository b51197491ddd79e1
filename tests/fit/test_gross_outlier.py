"""`cistrack fit` on a campaign with one observation a degree off: the filter takes it in and goes
astray; the least squares starts from the filter's final estimate or, where that fit fails, from the
filter's estimate before that update, rejects the observation and puts the truth inside its
covariance (examples/real-data/check_fit.py). Which start the fit needs depends on the last bits of
the arithmetic (the filter's diverged estimate lies far from the arc): the run's estimates must offer
the earlier estimate either way."""
from __future__ import annotations

import json
from datetime import datetime
import subprocess
import sys
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.fitting.restart import restart_points

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "real-data"
sys.path.insert(0, str(EXAMPLES))
from displace_observations import displace  # noqa: E402
from make_observations import make  # noqa: E402


@pytest.fixture(scope="module")
def gross_fit(tmp_path_factory):
    d = tmp_path_factory.mktemp("gross")
    make(d / "campaign", seed=177, sites=("J04", "568"))
    displaced = displace(d / "campaign" / "observations.psv", d / "gross.psv", fraction=0.014, lo=3000.0,
                         hi=3600.0, seed=177)
    # the filter over every observation: over the first hours only (the default) it never meets the outlier
    code = main(["fit", str(d / "gross.psv"), "--out", str(d / "fit"), "--quiet", "--set", "fit.filter_span=all"])
    return d, displaced, code


def test_the_fit_converges_with_the_outlier_rejected_after_the_filter_went_astray(gross_fit):
    d, displaced, code = gross_fit
    assert code == 0
    rec = json.loads((d / "fit" / "fit.json").read_text())
    assert rec["filter"]["verdict"] in ("diverged", "filter-failed", "lost-custody")
    assert rec["converged"] and rec["n_rejected"] >= len(displaced) == 1


def test_a_restart_is_said_with_the_update_it_avoids(gross_fit):
    d, _, _ = gross_fit
    start = json.loads((d / "fit" / "fit.json").read_text())["least_squares_start"]
    assert start == "the filter's final estimate" or (
        start.startswith("the filter's estimate at ") and "whose NIS" in start
        and "from the filter's final estimate" in start)


def test_the_run_offers_the_estimate_before_the_update_that_took_the_outlier_in(gross_fit):
    d, displaced, _ = gross_fit
    points = restart_points(d / "fit")
    assert points and "whose NIS" in points[0].why
    when = datetime.fromisoformat(points[0].why.split("update at ")[1].split("Z")[0])
    assert abs((when - _row_time(d / "gross.psv", displaced[0])).total_seconds()) < 1.0


def _row_time(psv: Path, index: int) -> datetime:
    """The time of observation ``index`` (time order) of an ADES PSV file."""
    lines = [ln.split("|") for ln in psv.read_text().splitlines() if ln and not ln.startswith("#")]
    col = lines[0].index("obsTime")
    times = sorted(datetime.fromisoformat(r[col].replace("Z", "")) for r in lines[1:])
    return times[index]


def test_the_restarted_fit_puts_the_truth_inside_its_covariance(gross_fit):
    d, _, code = gross_fit
    assert main(["export", str(d / "fit"), "--format", "oem"]) == 0
    check = subprocess.run([sys.executable, str(EXAMPLES / "check_fit.py"), str(d / "fit"), "--truth",
                            str(d / "campaign" / "truth.csv")], capture_output=True, text=True, timeout=300)
    assert check.returncode == 0, check.stdout[-1500:] + check.stderr[-1500:]
    assert "all bounds hold" in check.stdout


def test_check_fit_names_what_is_missing_instead_of_a_traceback(tmp_path):
    check = subprocess.run([sys.executable, str(EXAMPLES / "check_fit.py"), str(tmp_path)],
                           capture_output=True, text=True, timeout=300)
    assert check.returncode != 0 and "Traceback" not in check.stderr
    assert "no fit.json" in check.stderr


def test_an_outlier_in_the_iods_own_pass_is_left_out_of_the_iod_and_the_fit_converges(tmp_path):
    make(tmp_path / "campaign", seed=191, sites=("J04", "568"))
    [row] = displace(tmp_path / "campaign" / "observations.psv", tmp_path / "gross.psv", fraction=0.014,
                     lo=3000.0, hi=3600.0, seed=191)
    assert main(["fit", str(tmp_path / "gross.psv"), "--out", str(tmp_path / "fit"), "--quiet"]) == 0
    manifest = json.loads((tmp_path / "fit" / "manifest.json").read_text())
    [left] = manifest["iod"]["screened_out"]
    assert left["index"] == row and 3000.0 <= left["offset_arcsec"] <= 3600.0
    rec = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert rec["converged"] and rec["least_squares_start"] == "the filter's final estimate"
