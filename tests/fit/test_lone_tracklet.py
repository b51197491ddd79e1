"""`cistrack fit` of a file that holds one lone tracklet (issue 49, gap 2).

One tracklet gives two angles and their rates, not the range and the range rate: no orbit. Before
this, `cistrack fit` ran the filter over the admissible region and a least squares from its
estimate, and printed "FAILED" with a 1.1e6 km 1-sigma ("no convergence within 30 iterations")
for the 5-exposure file below; with 3 or 4 exposures such a fit can even meet its convergence
test. Now it runs nothing, says in words (summary and ``fit.json``) that one tracklet does not
determine an orbit, reports the tracklet's place and motion on the sky and the ranges and range
rates of its admissible region, and exits with status 3.

The tracklet: the first night of the survey set halo seed 23 (``examples/survey-sets``,
``make_survey_sets.py --family halo --seed 23``): MPC 711, 5 exposures over 14 minutes, the
object at 309,401 km from the site (``set.json``, ``range_km_first``).
"""
from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.sites import observatory
from cistrack.cli.main import main
from cistrack.fitting.determination import is_lone_tracklet, sky_motion
from cistrack.model.measurement import MeasurementSet

HEADER = "# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
ROWS = """halo|CCD|711|2026-08-08T10:10:54.459251Z|79.45130697317135|28.619129966967737|0.648|0.648|Gaia3
halo|CCD|711|2026-08-08T10:14:32.774891Z|79.49241394217094|28.6267601916247|0.648|0.648|Gaia3
halo|CCD|711|2026-08-08T10:18:01.093644Z|79.53137355766705|28.634043338470014|0.648|0.648|Gaia3
halo|CCD|711|2026-08-08T10:21:39.024066Z|79.57139671403115|28.641528209989085|0.648|0.648|Gaia3
halo|CCD|711|2026-08-08T10:24:58.449269Z|79.60808182463204|28.64818743448742|0.648|0.648|Gaia3
""".splitlines()
TRUE_RANGE_KM = 309401.4


def _fit(tmp_path, rows: list[str]):
    """(exit status, stdout, fit.json) of `cistrack fit` of a file of ``rows``."""
    f = tmp_path / "lone.psv"
    f.write_text(HEADER + "\n".join(rows) + "\n")
    buf = io.StringIO()
    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "stdout", buf)
    try:
        rc = main(["fit", str(f), "--out", str(tmp_path / "out")])
    finally:
        mp.undo()
    return rc, buf.getvalue(), json.loads((tmp_path / "out" / "fit.json").read_text())


@pytest.mark.parametrize("n", [5, 3])
def test_one_tracklet_is_reported_undetermined(tmp_path, n):
    rc, out, rec = _fit(tmp_path, ROWS[:n])
    assert rc == 3
    assert "UNDETERMINED: one tracklet does not determine an orbit" in out and "converged" not in out
    assert "next: cistrack export" not in out
    assert rec["converged"] is False and "state" not in rec and "covariance" not in rec
    assert rec["failure"].startswith("one tracklet does not determine an orbit")
    u = rec["undetermined"]
    assert u["sentence"] == rec["failure"]
    lo, hi = u["admissible_region"]["range_km"]
    assert lo < TRUE_RANGE_KM < hi                               # the truth lies in the region
    rlo, rhi = u["admissible_region"]["range_rate_kms"]
    assert rlo < 0.0 < rhi
    sky = u["tracklet"]
    assert sky["n_observations"] == n and sky["site"] == "711"
    # the rates: RA x cos(Dec) and Dec from the first to the last exposure, arcsec per minute
    first, last = (r.split("|") for r in (ROWS[0], ROWS[n - 1]))
    minutes = (units.parse_utc(last[3]) - units.parse_utc(first[3])).total_seconds() / 60.0
    dec = np.radians(0.5 * (float(first[5]) + float(last[5])))
    east = (float(last[4]) - float(first[4])) * 3600.0 * np.cos(dec) / minutes
    north = (float(last[5]) - float(first[5])) * 3600.0 / minutes
    assert sky["ra_cos_dec_rate_arcsec_min"] == pytest.approx(east, rel=0.02)
    assert sky["dec_rate_arcsec_min"] == pytest.approx(north, rel=0.02)
    assert f"{lo:,.0f}" in out and f"{hi:,.0f}" in out


def test_the_log_says_only_fit_json_is_written(tmp_path, capsys):
    """It had said "writing fit.json, residuals.csv and the residual plots", and wrote fit.json alone."""
    f = tmp_path / "lone.psv"
    f.write_text(HEADER + "\n".join(ROWS[:3]) + "\n")
    assert main(["fit", str(f), "--out", str(tmp_path / "out")]) == 3
    said = capsys.readouterr()
    assert f"writing fit.json to {tmp_path / 'out'}" in said.out + said.err
    assert not (tmp_path / "out" / "residuals.csv").exists()


def test_a_refused_export_names_the_reason(tmp_path):
    rc, _out, _rec = _fit(tmp_path, ROWS)
    assert rc == 3
    buf = io.StringIO()
    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "stderr", buf)
    try:
        assert main(["export", str(tmp_path / "out"), "--format", "oem"]) != 0
    finally:
        mp.undo()
    assert "one tracklet does not determine an orbit" in buf.getvalue()


def _set(times_h, sites) -> MeasurementSet:
    t = np.asarray(times_h, dtype=float) * 3600.0 / units.TU_S
    k = t.size
    values = np.column_stack([np.linspace(1.0, 1.001, k), np.linspace(0.3, 0.3005, k)])
    table = {code: observatory(code) for code in set(sites)}
    return MeasurementSet(t, values, np.full((k, 2), 1e-6), ("ra", "declination"), sites=np.asarray(sites),
                          kinds=np.full(k, "radec"), site_table=table)


def test_what_counts_as_one_tracklet():
    assert is_lone_tracklet(_set([0.0, 0.1, 0.2], ["711"] * 3))
    assert not is_lone_tracklet(_set([0.0, 0.1, 0.2], ["711", "711", "809"]))      # a second site: parallax
    assert not is_lone_tracklet(_set([0.0, 1.0, 2.5], ["711"] * 3))               # longer than 2 hours
    assert not is_lone_tracklet(_set([0.0, 0.1, 24.0, 24.1], ["711"] * 4))        # two nights


def test_sky_motion_of_a_straight_track():
    ms = _set([0.0, 0.25, 0.5], ["711"] * 3)
    sky = sky_motion(ms, units.parse_utc("2026-01-01T00:00:00Z"))
    rad_per_min = 0.001 / 30.0
    assert sky["ra_cos_dec_rate_arcsec_min"] == pytest.approx(rad_per_min * np.cos(0.30025) / units.ARCSEC_RAD, rel=1e-3)
    assert sky["dec_rate_arcsec_min"] == pytest.approx(0.0005 / 30.0 / units.ARCSEC_RAD, rel=1e-9)
    assert sky["span_minutes"] == pytest.approx(30.0) and sky["n_observations"] == 3


def test_one_exposure_measures_no_motion():
    """It had been printed as 0 "/min with a position angle of 0 deg."""
    sky = sky_motion(_set([0.0], ["711"]), units.parse_utc("2026-01-01T00:00:00Z"))
    assert sky["n_observations"] == 1 and sky["rate_arcsec_min"] is None and sky["position_angle_deg"] is None


def test_a_gross_outlier_in_the_tracklet_is_named(tmp_path):
    """The ranging IOD's curve through the exposures (a parabola for 4 or more) flags one 180" off."""
    rows = [r.split("|") for r in ROWS]
    rows[2][5] = repr(float(rows[2][5]) + 0.05)
    rc, out, rec = _fit(tmp_path, ["|".join(r) for r in rows])
    assert rc == 3 and rec["undetermined"]["tracklet"]["consistent"] is False
    assert "miss their own curve" in rec["failure"]


def test_a_clean_tracklet_lies_on_its_curve(tmp_path):
    _rc, _out, rec = _fit(tmp_path, ROWS)
    assert rec["undetermined"]["tracklet"]["consistent"] is True
    assert rec["undetermined"]["tracklet"]["misfit_sigma"] < 5.0


def test_a_lone_tracklet_long_after_a_determined_arc_leaves_that_arc_fitted(tmp_path):
    """The shipped five-night file plus one exposure a year later: the latest long-gap arc is that
    lone tracklet, which determines nothing; the fit is the arc before it, and says what it left."""
    shipped = (Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv").read_text().splitlines()
    rows = [r for r in shipped if r and not r.startswith("#") and "|" in r][1:]
    late = rows[0].split("|")
    late[3] = "2027-03-01T22:35:00Z"
    rc, out, rec = _fit(tmp_path, rows + ["|".join(late)])
    assert rc == 0 and rec["converged"] is True
    assert rec["n_used"] + rec["n_rejected"] == len(rows)
    note = next(m for m in rec["messages"] if "lone tracklet" in m)
    assert "1 observation(s) after the fitted arc" in note and "2027-03-01" in note


def test_a_lone_tracklet_too_fast_for_any_orbit_is_undetermined_with_the_reason(tmp_path):
    """Four exposures 10 s apart moving 5 degrees each (a near-Earth object, or wrong times): no range
    admits an orbit, so the admissible region is empty; said, not a traceback."""
    rows = [f"fast|CCD|711|2026-08-08T10:10:{10 * j:02d}.000Z|{79.0 + 5 * j:.6f}|{28.0 + j:.6f}|0.648|0.648|Gaia3"
            for j in range(4)]
    rc, out, rec = _fit(tmp_path, rows)
    assert rc == 3
    assert "UNDETERMINED: one tracklet does not determine an orbit" in out
    assert "admits no orbit" in out and "near-Earth object, or exposures with wrong times" in out
    assert "state" not in rec


AZEL_ROWS = """time_utc,azimuth_deg,elevation_deg,site
2026-03-01T22:35:00.000000Z,74.6056622,10.6168784,809
2026-03-01T23:32:15.702808Z,66.6783880,22.1667394,809
2026-03-02T00:14:46.637630Z,59.6543432,30.3121698,809
"""


def test_a_lone_azel_tracklet_is_undetermined_like_a_radec_one(tmp_path, capsys):
    """Probe L1: the real-data campaign's first three 809 observations as azimuth/elevation (CSV) had
    been fitted "converged; poorly determined" with 0 degrees of freedom and an Earth impact; the same
    three as RA/Dec were UNDETERMINED. Two angles are two angles: one tracklet, no orbit."""
    f = tmp_path / "azel.csv"
    f.write_text(AZEL_ROWS)
    assert main(["fit", str(f), "--out", str(tmp_path / "out")]) == 3
    out = capsys.readouterr().out
    rec = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert "UNDETERMINED: one tracklet does not determine an orbit" in out and "converged" not in out
    assert "state" not in rec and rec["failure"].startswith("one tracklet does not determine an orbit")
    sky = rec["undetermined"]["tracklet"]
    assert sky["angles"] == "azel" and sky["ra_deg"] is None and sky["rate_arcsec_min"] is None
    assert 59.6 < sky["azimuth_deg"] < 74.7 and 10.6 < sky["elevation_deg"] < 30.4
    assert "azimuth 66." in out


def test_an_azel_tracklet_counts_as_one_tracklet():
    ms = _set([0.0, 0.1, 0.2], ["711"] * 3)
    azel = MeasurementSet(ms.times, ms.values, np.full((3, 2), 1e-6), ("azimuth", "elevation"),
                          sites=np.asarray(["711"] * 3), kinds=np.full(3, "azel"), site_table=ms.site_table)
    assert is_lone_tracklet(azel)


def test_a_designation_of_100000_characters_is_cut_in_every_line_said(tmp_path, capsys):
    """Probe L10: such a trkSub had been echoed whole about six times (611,867 bytes of output); the
    fit.json keeps it whole."""
    name = "A" * 100_000
    f = tmp_path / "long.psv"
    f.write_text(HEADER + "\n".join(name + r[4:] for r in ROWS[:3]) + "\n")
    assert main(["fit", str(f), "--out", str(tmp_path / "out")]) == 3
    said = capsys.readouterr()
    assert "A" * 41 not in said.out + said.err
    assert f"fit {'A' * 30}...{'A' * 10} (100,000 characters): UNDETERMINED" in said.out
    assert json.loads((tmp_path / "out" / "fit.json").read_text())["designation"] == name
