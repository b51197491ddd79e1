"""The least squares keeps the residuals and the Jacobian of the points it has evaluated
(differential_correction._Problem): asked again at a point, it gives the numbers a fresh
evaluation gives, bit for bit, and what a caller does to them does not reach the next caller."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.least_squares.differential_correction import _KEPT_POINTS, _Problem
from cistrack.least_squares.measurement_model import MeasurementModel

from .arcs import GUESS_OFFSET, cr3bp_arc


def _problem() -> _Problem:
    arc = cr3bp_arc()
    return _Problem(arc.dynamics, MeasurementModel(arc.sensor, arc.exact), 0.0, None)


@pytest.fixture(scope="module")
def points():
    x0 = cr3bp_arc().truth0
    return [x0 + k * GUESS_OFFSET for k in range(_KEPT_POINTS + 2)]


def test_a_point_asked_again_gives_a_fresh_evaluations_numbers(points):
    prob = _problem()
    for x in points + points[::-1]:                  # kept, dropped and evaluated again
        w, states = prob.evaluate(x)
        w_new, states_new = _problem().evaluate(x)
        assert np.array_equal(w, w_new) and np.array_equal(states, states_new)


def test_a_jacobian_asked_again_is_a_fresh_ones(points):
    prob = _problem()
    for x in points[:2] + points[:2]:
        assert np.array_equal(prob.jacobian(x), _problem().jacobian(x))


def test_changing_the_returned_arrays_leaves_the_kept_ones(points):
    prob = _problem()
    w, states = prob.evaluate(points[0])
    a = prob.jacobian(points[0])
    want = (w.copy(), states.copy(), a.copy())
    for arr in (w, states, a):
        arr[...] = np.nan
    w2, states2 = prob.evaluate(points[0])
    assert np.array_equal(w2, want[0]) and np.array_equal(states2, want[1])
    assert np.array_equal(prob.jacobian(points[0]), want[2])
