"""A burn made shortly before a night's first tracklet: the burn time check
(:func:`cistrack.least_squares.burn_search.times_allowed`) fits times close before that tracklet,
not only the night gap's evenly spaced ones, which lie hours from the night.

Survey set halo seed 2100 with a 1.5 m/s burn 53 minutes before the first observation of its
fifth night (``make_survey_sets.py --burn-before-night 53``): the search placed the burn after
that night's first tracklet, at 06:49 +- 9.9 min against the truth's 05:32 (time z +7.8), and the
fit said "well determined"; the nearest time the check fitted before the night lay 3.9 hours
before it (the 46-hour gap's six evenly spaced times). A burn an hour before the tracklet fits within the check's three-sigma cost, and the
time's sigma now reaches it.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from cistrack import units
from cistrack.least_squares.burn_search import _trial_times, _windows
from cistrack.runs.observation_files import read_observations

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "survey-sets"


def _tu(hours) -> np.ndarray:
    return np.asarray(units.hours_to_tu(np.asarray(hours, dtype=float)), dtype=float)


def test_times_close_before_the_night_holding_the_window_are_tried():
    # tracklets at 0 h, 24 h and 26 h (exposures 6 minutes apart), then 48 h; the burn placed
    # between the second night's two tracklets
    t = _tu([0.0, 0.1, 0.2, 24.0, 24.1, 24.2, 26.0, 26.1, 26.2, 48.0, 48.1, 48.2])
    night_before, window, night_after = _windows(t, [])
    trial = np.array(_trial_times(t, window, []))
    minutes_before = (t[3] - trial) * units.TU_S / 60.0
    minutes_after = (trial - t[8]) * units.TU_S / 60.0
    for m in (10.0, 30.0, 60.0):                                    # burn_search.EDGE_MINUTES
        assert np.isclose(minutes_before, m).sum() == 1, (m, np.sort(minutes_before))
        assert np.isclose(minutes_after, m).sum() == 1, (m, np.sort(minutes_after))
    assert all(night_before[0] < x < night_after[1] for x in trial)


def test_a_burn_in_a_nights_gap_gets_no_edge_times_beyond_the_arc():
    t = _tu([0.0, 0.1, 0.2, 24.0, 24.1, 24.2])                       # two nights: one gap
    (gap,) = _windows(t, [])
    trial = _trial_times(t, gap, [])
    assert len(trial) == 6 and all(gap[0] < x < gap[1] for x in trial)


@pytest.mark.slow
def test_a_burn_53_minutes_before_a_nights_first_tracklet_is_measured(tmp_path):
    sys.path.insert(0, str(EXAMPLES))
    from check_survey_fit import MAHALANOBIS2_BOUND, check_set
    from make_survey_sets import make

    set_dir = tmp_path / "halo-s2100"
    info = make(set_dir, "halo", seed=2100, burn_ms=1.5, burn_before_night=53.0)
    epoch = units.parse_utc(info["epoch"])
    ms = read_observations(set_dir / "observations.psv", info["epoch"])
    t_burn = units.utc_to_tu(epoch, units.parse_utc(info["burn"]["utc"]))
    after = (ms.times[ms.times > t_burn].min() - t_burn) * units.TU_S / 60.0
    assert after == pytest.approx(53.0, abs=1e-3)                      # the next observation: 53 min later
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert row.burns.startswith("1:") and row.burn_ok, row.burns     # time and size within 3 sigma
    assert row.max_m2 <= MAHALANOBIS2_BOUND, row.max_m2
