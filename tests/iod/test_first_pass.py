"""Choosing the fitted measurements: the first part of the first pass."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import IODError
from cistrack.plugins.iod.first_pass import first_pass_length, select_fit_indices
from cistrack.units import hours_to_tu

HOUR = float(hours_to_tu(1.0))


def _times(n_first: int, n_second: int = 5, step_h: float = 0.75, gap_h: float = 14.0):
    first = np.arange(n_first) * step_h * HOUR
    second = first[-1] + gap_h * HOUR + np.arange(n_second) * step_h * HOUR
    return np.concatenate([first, second])


def test_first_pass_ends_at_the_first_gap_longer_than_the_threshold():
    assert first_pass_length(_times(14), pass_gap_hours=3.0) == 14


def test_a_gap_shorter_than_the_threshold_does_not_end_the_pass():
    assert first_pass_length(_times(14, gap_h=2.0), pass_gap_hours=3.0) == 19


def test_half_of_the_pass_is_fitted_within_min_and_max():
    assert select_fit_indices(_times(20)).tolist() == list(range(10))
    assert len(select_fit_indices(_times(14))) == 8      # 7 clipped up to min_fit
    assert len(select_fit_indices(_times(40))) == 12     # 20 clipped down to max_fit


def test_a_first_pass_with_too_few_measurements_is_refused_with_the_count():
    with pytest.raises(IODError, match="first pass has 6 measurement"):
        select_fit_indices(_times(6))


def test_a_pass_too_short_for_the_order_is_refused():
    with pytest.raises(IODError, match="order 6 needs 7"):
        select_fit_indices(_times(6), min_fit=3, order=6)


def test_non_monotonic_times_are_refused():
    t = _times(14)
    t[3], t[4] = t[4], t[3]
    with pytest.raises(IODError, match="increase strictly"):
        select_fit_indices(t)


def test_no_measurements_is_refused():
    with pytest.raises(IODError, match="no measurements"):
        select_fit_indices(np.array([]))
