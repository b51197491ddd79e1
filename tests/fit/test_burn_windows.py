"""The intervals the burn search places a burn in (:func:`cistrack.least_squares.burn_search._windows`):
every gap of at least 12 minutes between observations, and every stretch of closer observations
spanning at least an hour as a whole (a pass of a dense campaign), never a survey tracklet's
10-30 minutes; a night's gap next to a dense stretch is still a night's gap for the time check."""
from __future__ import annotations

import numpy as np

from cistrack import units
from cistrack.least_squares.burn_search import _trial_times, _windows


def _tu(hours) -> np.ndarray:
    return np.asarray(units.hours_to_tu(np.asarray(hours, dtype=float)), dtype=float)


def test_tracklets_of_a_survey_give_the_gaps_between_them_only():
    t = _tu([0.0, 0.1, 0.2, 0.3, 2.0, 2.15, 2.3, 26.0, 26.1, 26.2])   # three tracklets, exposures 6-9 minutes apart
    assert _windows(t, []) == [(t[3], t[4]), (t[6], t[7])]


def test_a_dense_pass_is_one_window_from_its_first_observation_to_its_last():
    dense = np.arange(0.0, 3.0, 0.1)                                   # every 6 minutes for 2.9 hours
    t = _tu(np.concatenate([dense, [20.0, 20.5]]))
    assert _windows(t, []) == [(t[0], t[len(dense) - 1]), (t[len(dense) - 1], t[-2]), (t[-2], t[-1])]


def test_windows_already_taken_are_left_out():
    t = _tu(np.concatenate([np.arange(0.0, 2.0, 0.1), [20.0]]))
    first, second = _windows(t, [])
    assert _windows(t, [first]) == [second]


def test_a_dense_pass_is_no_nights_gap_in_the_burn_time_check():
    t = _tu(np.concatenate([np.arange(0.0, 5.0, 0.1), [24.0, 24.5], np.arange(48.0, 53.0, 0.1)]))
    first_pass, far_gap, _short, near_gap, last_pass = _windows(t, [])
    trial = _trial_times(t, last_pass, [])                              # the burn placed in the last dense pass

    def count(w):
        return sum(w[0] < x < w[1] for x in trial)

    assert count(last_pass) == 6 and count(near_gap) == 6 + 3            # its window and the nearest night's gap:
    hour_before = (last_pass[0] - units.hours_to_tu(1.01), last_pass[0])  # 3 of the latter within its last hour
    assert count(hour_before) == 3
    assert count(far_gap) == 3                                           # every other night's gap
    assert count(first_pass) == 0                                        # a dense pass is no night's gap
