"""Measurement residuals of a run without a truth (issue 16, item 3).

A real run of the ``quick`` scenario (3 days, two passes after the IOD pass) simulates noisy
angles of a known truth; its measurements are written to a CSV file and run again as an
observation file, without a truth. The residuals that run reports are then checked against what
was simulated: each residual is the injected noise plus the prior's prediction error, so it must
lie within its stated spread, and where the prior is tight the residual is the noise itself.
"""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.plugins.readers.csv_file import write_measurements
from cistrack.evaluation.residuals import ARCSEC_PER_RAD, residual_summary
from cistrack.results.store import read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SIGMA_ARCSEC = 1.5


@pytest.fixture(scope="module")
def truthless(tmp_path_factory):
    """(the run with a truth, the file run's update rows, the file run's directory, the CSV)."""
    tmp = tmp_path_factory.mktemp("residuals")
    base = load_scenario("quick").with_overrides({"duration_days": 3.0})
    sim = run_scenario(base, seed=1)
    obs = tmp / "obs.csv"
    write_measurements(obs, sim.context.measurements, "2026-01-01T00:00:00Z")
    out = tmp / "run"
    run_scenario(base.with_overrides({"measurements": {"file": str(obs)}}), seed=1, output_dir=out)
    rows = [r for r in read_steps(out).to_pylist() if r["kind"] == "update"]
    return sim, rows, out, obs


def _injected_noise_arcsec(sim, index: int) -> np.ndarray:
    """z - h(truth) of measurement ``index`` of the simulated run (azimuth, elevation), arcsec."""
    ctx = sim.context
    t = float(ctx.measurements.times[index])
    h = ctx.sensor.measure(ctx.truth.states_at([t]), t)[0]
    z = np.asarray(ctx.measurements.values[index], dtype=float)
    return (ctx.sensor.residual(z, h) * ARCSEC_PER_RAD)[:2]


def _pair(row, prefix):
    return np.array([row[f"{prefix}_azimuth_arcsec"], row[f"{prefix}_elevation_arcsec"]])


def test_every_update_of_a_truthless_run_has_residuals_spreads_and_nis_in_its_steps_table(truthless):
    _, rows, _, _ = truthless
    assert len(rows) >= 10
    for r in rows:
        assert np.all(np.isfinite(_pair(r, "res"))) and np.all(_pair(r, "sd") > 0)
        assert r["nis_dof"] == 2 and np.isfinite(r["nis"])
        assert r["nis_outside_95"] == float(not chi2.ppf(0.025, 2) <= r["nis"] <= chi2.ppf(0.975, 2))
        assert "custody" not in r


def test_the_predicted_spread_includes_the_measurement_noise(truthless):
    _, rows, _, _ = truthless
    assert min(min(_pair(r, "sd")) for r in rows) >= SIGMA_ARCSEC * (1 - 1e-9)


def test_residual_minus_injected_noise_lies_within_the_priors_stated_spread(truthless):
    sim, rows, _, _ = truthless
    for r in rows:
        pred_err = _pair(r, "res") - _injected_noise_arcsec(sim, int(r["measurement_index"]))  # h(truth) - z_hat
        prior_sd = np.sqrt(_pair(r, "sd") ** 2 - SIGMA_ARCSEC ** 2)
        assert np.all(np.abs(pred_err) <= 4.0 * prior_sd + 1e-6), (r["t_days"], pred_err, prior_sd)


def test_where_the_prior_is_tight_the_residuals_are_the_1_5_arcsec_noise(truthless):
    sim, rows, _, _ = truthless
    tight = [r for r in rows if max(_pair(r, "sd")) < 4.0 * SIGMA_ARCSEC]
    assert len(tight) >= 6
    res = np.array([_pair(r, "res") for r in tight]).ravel()
    assert np.all(np.abs(res) < 5.0 * 4.0 * SIGMA_ARCSEC)
    z = np.array([_pair(r, "res") / _pair(r, "sd") for r in tight]).ravel()   # ~ N(0, 1) if consistent
    assert abs(z.mean()) < 3.0 / np.sqrt(z.size) + 0.3 and 0.4 < z.std() < 1.8


def test_residual_summary_counts_measurements_outside_their_bounds_and_the_largest_residual(truthless):
    _, rows, _, _ = truthless
    s = residual_summary(rows)
    assert s.n == len(rows) and s.nis_test.dof == 2
    assert s.nis_test.mean == pytest.approx(np.mean([r["nis"] for r in rows]))
    assert s.share_outside_95 == pytest.approx(np.mean([r["nis_outside_95"] for r in rows]))
    assert s.max_abs_residual_arcsec == pytest.approx(max(np.abs(_pair(r, "res")).max() for r in rows))


def test_the_largest_residual_is_reported_beside_the_spread_predicted_for_it(truthless):
    _, rows, _, _ = truthless
    s = residual_summary(rows)
    row = max(rows, key=lambda r: np.abs(_pair(r, "res")).max())
    axis = int(np.argmax(np.abs(_pair(row, "res"))))
    assert s.max_abs_residual_sd_arcsec == pytest.approx(_pair(row, "sd")[axis])
    assert s.max_abs_residual_t_days == pytest.approx(row["t_days"])
    assert s.max_residual_sigma == pytest.approx(max((np.abs(_pair(r, "res")) / _pair(r, "sd")).max() for r in rows))


def test_the_cli_summarises_residuals_of_a_truthless_run_without_speaking_of_custody(truthless, tmp_path):
    _, _, _, obs = truthless
    out = tmp_path / "cli"
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out),
                           "--set", "duration_days=3.0", "--set", f"measurements.file={obs}"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "custody" not in (proc.stdout + proc.stderr).lower()
    s = residual_summary(read_steps(out).to_pylist())
    assert f"mean NIS {s.nis_test.mean:.3g}" in proc.stdout
    said = " ".join(proc.stdout.split())  # the line is wrapped within 120 columns
    assert (f"{100 * s.share_outside_95:.0f} % of measurements outside their 95 % NIS bounds" in said
            and f"largest |residual| {s.max_abs_residual_arcsec:.3g} arcsec" in said)
