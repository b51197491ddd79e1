"""A poorly determined fit follows its line of variations until the data rule it out, and takes a
better solution found along it (cistrack.fitting.lov_solutions).

The night below (11 observations of an NRHO object from one site over 4 hours, survey set seed 31)
first converges to a minimum 30,000 km from the truth; the line, followed past its linear 3 sigma,
falls to a second minimum with a lower chi-square, where the truth is. The truth state at the fit
epoch is the survey generator's, propagated from its truth file by the ephemeris dynamics."""
from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.fitting.lov_solutions import AUTO_DELTA_CHI2
from cistrack.least_squares.line_of_variations import widened_to_hold
from cistrack.least_squares.line_of_variations import LovPoint, line_minima, line_reach

NIGHT = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
nrho|CCD|M22|2026-05-01T17:15:59.985810Z|215.43149293489537|-19.59906428343243|0.706000688421532|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T17:23:33.631543Z|215.47228846931684|-19.635680347753723|0.7060007456999562|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T17:30:28.039985Z|215.50872394412558|-19.669564551349132|0.7059986315704005|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T17:37:33.241460Z|215.54622807468488|-19.70350162108151|0.70599983888149505|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T17:45:02.442055Z|215.5848540417927|-19.739355481916017|0.7060007780837669|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T19:20:50.195725Z|216.02242880044964|-20.191120670496534|0.7059993686316281|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T19:24:26.239642Z|216.0371815619612|-20.207772159249586|0.70599867661295595|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T19:28:44.932542Z|216.05464664554633|-20.22722549209306|0.70599980392862176|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T21:03:42.483993Z|216.40123996600983|-20.643952995057916|0.7059999371725041|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T21:10:22.178244Z|216.42320640600218|-20.67177871381543|0.7060000984831107|0.706000000000|Gaia3
nrho|CCD|M22|2026-05-01T21:16:58.295395Z|216.44492822406416|-20.699219892108853|0.7059999868815538|0.706000000000|Gaia3
"""
TRUTH_KM = np.array([466737.92227257066, -17809.541877037416, -13217.365417233465,
                     0.1517535302327682, -0.22733128857880497, -0.2059672713861134])
"""The truth at the fit epoch 2026-05-01T21:16:58.295395Z (the last observation), synodic km, km/s."""
CHI2_6_DOF_99 = 16.81


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("lov")
    (d / "night.psv").write_text(NIGHT)
    assert main(["fit", str(d / "night.psv"), "--out", str(d / "fit"), "--quiet"]) == 0
    return d / "fit", json.loads((d / "fit" / "fit.json").read_text())


def _mahalanobis2(record) -> float:
    e = TRUTH_KM - np.asarray(record["state_km"])
    return float(e @ np.linalg.solve(np.asarray(record["covariance_km"]), e))


def test_the_better_solution_along_the_line_is_taken_and_holds_the_truth(fitted):
    _, record = fitted
    assert any(m.startswith("a better solution along the line of variations") for m in record["messages"])
    assert _mahalanobis2(record) < CHI2_6_DOF_99


def test_the_first_solution_is_reported_as_another_minimum_of_the_line(fitted):
    _, record = fitted
    other = record["line_of_variations"]["minima"][1]
    assert 2.0 < other["delta_chi2"] < 5.0 and other["offset_km"] > 20_000.0 and not other["at_end"]


def test_the_line_goes_on_until_the_chi_square_has_risen_past_3_sigma(fitted):
    d, record = fitted
    with (d / "lov.csv").open() as fh:
        rise = [float(r["delta_chi2"]) for r in csv.DictReader(fh)]
    assert min(rise[0], rise[-1]) > 9.0 and max(rise) <= AUTO_DELTA_CHI2 and len(rise) > 13
    assert not record["line_of_variations"]["reach"]["open"]


def _points(chi2: list[float]) -> list[LovPoint]:
    """Points one sigma apart along x (LU), with the given chi-squares."""
    return [LovPoint(float(k), np.array([0.01 * k, 0, 0, 0, 0, 0]), c, np.eye(6))
            for k, c in zip(range(-(len(chi2) // 2), len(chi2)), chi2)]


def test_the_minima_of_a_two_valley_line_are_named_lowest_first():
    minima = line_minima(_points([9.0, 4.0, 1.0, 3.0, 0.0, 2.0, 8.0]))
    assert [m["sigma"] for m in minima] == [1.0, -1.0]
    assert minima[1]["delta_chi2"] == pytest.approx(1.0) and minima[1]["offset_km"] == pytest.approx(0.02 * 384_400.0)


def test_an_end_point_that_still_falls_is_a_minimum_at_the_end():
    minima = line_minima(_points([5.0, 3.0, 0.0, 2.0, 1.0]))
    assert [(m["sigma"], m["at_end"]) for m in minima] == [(0.0, False), (2.0, True)]


def test_the_reach_holds_the_points_within_9_of_the_lowest_and_says_when_it_is_open():
    closed = line_reach(_points([12.0, 8.0, 0.0, 5.0, 10.0]))
    assert closed["sigma_range"] == [-1.0, 1.0] and not closed["open"]
    assert line_reach(_points([3.0, 0.0, 5.0]))["open"]


def test_a_widened_sky_covariance_holds_every_offset_at_3_sigma():
    cov = np.diag([4.0, 1.0])
    d = np.array([[300.0, 40.0], [-120.0, -10.0], [5.0, 1.0]])
    wide = widened_to_hold(cov, d)
    assert np.max(np.einsum("mi,ij,mj->m", d, np.linalg.inv(wide), d)) <= 9.0
    assert np.max(np.einsum("mi,ij,mj->m", d, np.linalg.inv(wide), d)) > 8.5  # no wider than needed


def test_a_sky_covariance_that_already_holds_the_line_is_kept():
    cov = np.diag([4.0, 1.0])
    assert widened_to_hold(cov, np.array([[2.0, 1.0]])) is cov


def test_the_horizon_is_drawn_along_the_line_and_is_shorter_than_the_covariances(fitted):
    _, record = fitted
    assert record["determination"]["horizon_days"] <= 0.5  # 1.2 days from the covariance's draws


def test_predict_widens_its_ellipses_to_hold_the_line(fitted, capsys):
    d, _ = fitted
    assert main(["predict", str(d), "--site", "M22", "--start", "2026-05-02T17:00:00Z", "--stop",
                 "2026-05-02T19:00:00Z", "--step", "60"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "the 3-sigma ellipses are widened to hold the orbits along it within 3 sigma" in out
    with (d / "sky-M22.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert all(float(r["line_reach_arcsec"]) > 0 for r in rows)
    assert all(float(r["semi_major_3sigma_arcsec"]) >= float(r["line_reach_arcsec"]) for r in rows)


def test_an_export_predicted_past_the_horizon_warns_on_the_terminal_and_in_the_file(fitted, capsys, tmp_path):
    d, _ = fitted
    oem = tmp_path / "p.oem"
    assert main(["export", str(d), "--format", "oem", "--predict", "2", "--out", str(oem)]) == 0
    said = "days past the last observation, beyond the fit's horizon of 0.5 days"
    assert said in capsys.readouterr().out and said in " ".join(oem.read_text().split())
    assert main(["export", str(d), "--format", "oem", "--predict", "0.25", "--out", str(tmp_path / "q.oem")]) == 0
    assert "horizon" not in capsys.readouterr().out


def _first_position_variance_km2(oem) -> float:
    lines = oem.read_text().splitlines()
    return float(lines[lines.index("COVARIANCE_START") + 2])


def test_an_export_widens_its_covariances_to_hold_the_line(fitted, tmp_path):
    d, _ = fitted
    assert main(["export", str(d), "--format", "oem", "--out", str(tmp_path / "w.oem")]) == 0
    text = " ".join((tmp_path / "w.oem").read_text().split())
    assert "each covariance here is widened to hold every orbit along the line within 3 sigma" in text
    linear = tmp_path / "linear"
    shutil.copytree(d, linear)
    (linear / "lov.csv").unlink()  # no line to hold: the linear covariance, with the warning that it understates
    assert main(["export", str(linear), "--format", "oem", "--out", str(tmp_path / "l.oem")]) == 0
    assert "the covariance understates the uncertainty" in " ".join((tmp_path / "l.oem").read_text().split())
    assert _first_position_variance_km2(tmp_path / "w.oem") > 4 * _first_position_variance_km2(tmp_path / "l.oem")


def _damaged(d, tmp_path, how):
    out = tmp_path / how
    shutil.copytree(d, out)
    lov = out / "lov.csv"
    if how == "huge":
        lines = lov.read_text().splitlines()
        cells = lines[2].split(",")
        cells[3] = "1e30"
        lov.write_text("\n".join(lines[:2] + [",".join(cells)] + lines[3:]) + "\n")
    else:
        lov.unlink()
        os.mkfifo(lov) if how == "fifo" else lov.symlink_to("/dev/zero")
    return out


@pytest.mark.parametrize("how", ["huge", "fifo", "zero"])
def test_a_damaged_line_file_leaves_the_linear_covariance_with_its_warning(fitted, tmp_path, how):
    d = _damaged(fitted[0], tmp_path, how)
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "export", str(d), "--format", "oem"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert "the covariance understates the uncertainty" in " ".join((d / "estimate.oem").read_text().split())


def test_a_line_drawn_short_of_its_reach_is_said_to_be_held_only_as_far_as_it_was_drawn(fitted, tmp_path):
    """A short fit.lov = N ends the line inside its 3-sigma reach (fit.json reach.open): the widened
    covariance holds the drawn part only, and the export says so."""
    d = tmp_path / "short"
    shutil.copytree(fitted[0], d)
    rec = json.loads((d / "fit.json").read_text())
    rec["line_of_variations"]["reach"]["open"] = True
    (d / "fit.json").write_text(json.dumps(rec))
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 0
    text = " ".join((d / "estimate.oem").read_text().replace("\nCOMMENT ", " ").split())
    assert "within 3 sigma, as far as it was drawn: the orbits the data allow go on beyond its end" in text


def test_the_line_is_cut_each_side_before_its_first_state_beyond_cislunar_space():
    """Huge stated uncertainties (1e5 arcsec) had drawn a line out to 4e7 km, which export and
    predict then refused as a damaged lov.csv; the fit writes only the part they read."""
    from cistrack.fitting.lov_solutions import within_cislunar_reach

    x_lu = {-2: -9.0, -1: -3.0, 0: 1.0, 1: 5.0, 2: 8.0, 3: 2.0}  # 3e6 km is 7.8 LU from the barycentre
    points = [LovPoint(float(k), np.array([x, 0, 0, 0, 0, 0]), 0.0, np.eye(6)) for k, x in x_lu.items()]
    assert [p.sigma for p in within_cislunar_reach(points)] == [-1.0, 0.0, 1.0]
