"""A gap-shrinking time axis for study figures: long gaps without measurements take a small fixed
width, short ones are untouched, and the mapping inverts exactly."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.studies.time_axis import GapAxis

DAYS = np.array([1.0, 1.1, 1.2, 2.0, 2.1, 152.0, 152.1, 153.0, 153.2])  # a 150-day shutoff


def test_a_long_gap_takes_the_given_share_of_what_the_axis_keeps():
    ax = GapAxis.from_times(DAYS, 1.0, 153.2, gap_width=0.04)
    assert ax.gaps.tolist() == [[2.1, 152.0]]
    kept = 152.2 - 149.9
    assert ax.width == pytest.approx(0.04 * kept)
    assert ax.forward(np.array(152.0)) - ax.forward(np.array(2.1)) == pytest.approx(ax.width)


def test_times_outside_the_gap_keep_their_spacing():
    ax = GapAxis.from_times(DAYS, 1.0, 153.2)
    assert ax.forward(np.array(153.2)) - ax.forward(np.array(152.1)) == pytest.approx(1.1)
    assert ax.forward(np.array(1.7)) == pytest.approx(1.7)


def test_the_inverse_undoes_the_mapping_inside_and_outside_gaps():
    ax = GapAxis.from_times(np.array([0.0, 1.0, 30.0, 31.0, 80.0, 81.0]), 0.0, 81.0, min_gap_days=10, min_fraction=0.1)
    assert ax.gaps.shape == (2, 2)
    t = np.linspace(0.0, 81.0, 997)
    np.testing.assert_allclose(ax.inverse(ax.forward(t)), t, atol=1e-9)


def test_short_gaps_are_left_alone():
    ax = GapAxis.from_times(np.array([0.0, 1.0, 2.5, 3.0]), 0.0, 3.0)
    assert not ax.shrinks
    np.testing.assert_array_equal(ax.forward(np.array([0.5, 2.9])), [0.5, 2.9])
