"""`cistrack fit` runs the filter over the first hours only and starts the least squares from its
estimate there (cistrack.fitting.early_seed): the same orbit as from the filter run over every
observation, the filter's span recorded in fit.json, and the full run when that fit is not clean."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.fitting.early_seed import MIN_LATER_SHARE, early_rows
from cistrack.fitting.from_observations import EARLY_FILE, fit_choices, fit_files
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
FAST = ["iod.n_particles=1000", "filter.n_particles=1000"]


def _hours(*h: float) -> np.ndarray:
    return np.asarray(units.hours_to_tu(np.array(h, dtype=float)))


def test_the_filter_takes_the_first_half_day():
    t = _hours(0, 1, 2, 5, 8, 11, 14, 15, 30, 31, 55, 56, 75, 76, 104, 105)
    assert early_rows(t) == 6                        # to 12 h, within the first session


def test_the_filter_takes_at_least_the_first_session():
    t = _hours(0, 1, 2, 3, 4, 30, 31, 55, 56, 75, 76, 104, 105)
    assert early_rows(t, days=0.1) == 5              # the IOD's pass, whole


def test_no_shortcut_when_it_leaves_too_few_observations_to_the_least_squares():
    t = _hours(0, 1, 2, 3, 4, 5, 6, 7, 30, 31)
    assert (len(t) - 8) < MIN_LATER_SHARE * len(t)
    assert early_rows(t) == 0
    assert early_rows(_hours(0, 1, 2)) == 0          # one session


def test_the_filter_span_defaults_to_early_and_all_is_accepted():
    assert fit_choices({}).filter_span == "early"
    assert fit_choices({"filter_span": "all"}).filter_span == "all"


def test_an_unknown_filter_span_is_refused_naming_the_choices():
    with pytest.raises(ConfigError, match="fit.filter_span='some'.*'early'.*'all'"):
        fit_choices({"filter_span": "some"})


@pytest.fixture(scope="module")
def both_fits(tmp_path_factory):
    """(fit seeded by the filter over the first hours, fit after the filter over every observation)
    of the shipped example, with their fit.json records."""
    d = tmp_path_factory.mktemp("seeding")
    (early,) = fit_files([DATA / "observations.psv"], out=d / "early", settings=FAST)
    (full,) = fit_files([DATA / "observations.psv"], out=d / "full", settings=FAST + ["fit.filter_span=all"])
    records = [json.loads((one.directory / "fit.json").read_text()) for one in (early, full)]
    return early, full, records


def test_the_filter_runs_over_the_first_hours_only(both_fits):
    early, full, (rec, rec_full) = both_fits
    assert early.ok and full.ok
    assert 0 < rec["filter"]["n_observations"] < rec["arc"]["n_observations"] == 65
    assert rec_full["filter"]["n_observations"] == 65
    assert (early.directory / f"{EARLY_FILE}.psv").exists()
    assert not (full.directory / f"{EARLY_FILE}.psv").exists()


def test_the_seeded_fit_is_the_full_runs_within_a_tenth_of_a_sigma(both_fits):
    early, full, _ = both_fits
    assert early.result.epoch == full.result.epoch
    d = early.result.state_km - full.result.state_km
    assert float(np.sqrt(d @ np.linalg.solve(full.result.covariance_km, d))) <= 0.1
    assert early.result.n_rejected == full.result.n_rejected


def test_the_fit_says_the_filter_ran_over_the_first_observations(both_fits):
    early, _, _ = both_fits
    assert any(f"then the filter over the first {early.filter_rows} observations" in m
               for m in early.result.messages)


def test_a_gross_outlier_after_the_first_hours_is_rejected_by_the_least_squares(tmp_path):
    import sys
    from pathlib import Path

    examples = Path(__file__).resolve().parents[2] / "examples" / "real-data"
    sys.path.insert(0, str(examples))
    from displace_observations import displace
    from make_observations import make

    make(tmp_path / "campaign", seed=177, sites=("J04", "568"))
    [row] = displace(tmp_path / "campaign" / "observations.psv", tmp_path / "gross.psv", fraction=0.014, lo=3000.0,
                     hi=3600.0, seed=177)
    (one,) = fit_files([tmp_path / "gross.psv"], out=tmp_path / "fit")
    assert one.ok and 0 < one.filter_rows <= row            # the filter stopped before the outlier
    assert one.result.residuals.rejected[row] and one.result.n_rejected <= 2


@pytest.mark.slow  # about two minutes of CPU: the first hours. run, then the full one
def test_a_fit_that_looks_like_a_maneuver_takes_the_filter_over_every_observation(tmp_path):
    from cistrack.runs.observation_files import write_observations

    from .arc_campaigns import two_weeks
    from .burn_campaigns import burned

    b = burned(0.3)
    write_observations(tmp_path / "obs.psv", b.measurements, two_weeks().epoch, format="ades-psv")
    (one,) = fit_files([tmp_path / "obs.psv"], out=tmp_path / "fit")
    record = json.loads((one.directory / "fit.json").read_text())
    assert one.filter_rows == 0 and record["filter"]["n_observations"] == len(b.measurements)
    assert len(record["maneuvers"]) == 1 and one.ok
