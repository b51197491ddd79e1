"""End to end on the 9:2 NRHO: noisy-range kinematic IOD, the paper's Example-1 tasking, the
CR3BP dynamics and the ground telescope. Over the first two passes each filter's
moment-matched NEES must lie inside the chi^2(6) 99 % band on most update steps."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

LO, HI = chi2.ppf([0.005, 0.995], 6)

FILTERS = {
    "pgm": {"name": "pgm", "n_particles": 5000, "n_components": 6},
    "enkf": {"name": "enkf", "n_particles": 1000},
    "ukf": {"name": "ukf"},   # iterated (posterior-linearised) update; with update_iterations=1 NEES ~85-110
}


@pytest.mark.slow
@pytest.mark.parametrize("filter_table", list(FILTERS.values()), ids=list(FILTERS))
def test_filter_is_consistent_over_the_first_two_passes(filter_table):
    scenario = load_scenario("quick").with_overrides({   # 9:2 NRHO, paper-example-1, 2 days
        "duration_days": 2.0,  # as written: quick became 3 days in session 8, which moves pass 2's measurements
        "filter": filter_table,
        "iod": {"name": "noisy-range", "n_particles": 5000},
    })
    result = run_scenario(scenario, seed=1)
    assert result.summary.status == "finished"
    updates = [r for r in result.rows if r["kind"] == "update"]
    passes = {r["pass_index"] for r in updates}
    assert {1.0, 2.0} <= passes
    nees = np.array([r["nees"] for r in updates])
    assert np.all(np.isfinite(nees))
    inside = (nees >= LO) & (nees <= HI)
    assert inside.mean() >= 2 / 3, nees


@pytest.mark.slow
def test_ukf_nees_averaged_over_ten_seeds_is_inside_the_chi2_band_on_every_step():
    """M = 10 runs: at each of the first 9 updates, M * mean(NEES) ~ chi^2(6M) (99 % band)."""
    seeds = range(1, 11)
    lo, hi = chi2.ppf([0.005, 0.995], 6 * len(seeds)) / len(seeds)
    per_run = []
    for seed in seeds:
        scenario = load_scenario("quick").with_overrides({
            "filter": {"name": "ukf"}, "iod": {"name": "noisy-range", "n_particles": 5000}})
        result = run_scenario(scenario, seed=seed)
        assert result.summary.status == "finished"
        per_run.append([r["nees"] for r in result.rows if r["kind"] == "update"][:9])
    mean = np.mean(np.array(per_run), axis=0)
    assert np.all((mean >= lo) & (mean <= hi)), mean
