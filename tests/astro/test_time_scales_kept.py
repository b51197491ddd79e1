"""time_scales keeps its recent results (a fit asks for the same observation times at every
iteration): asked again it returns the numbers of a fresh evaluation, as copies, and never those
computed with another Earth orientation table."""
from __future__ import annotations

import numpy as np
from astropy.utils import iers

from cistrack.astro import timescales as ts

EPOCH = "2025-03-01T00:00:00Z"


def _fields(sc) -> list[np.ndarray]:
    eo = sc.orientation
    return [*sc.utc, *sc.tt, *sc.tdb, *sc.ut1, eo.ut1_minus_utc, eo.xp, eo.yp, eo.tabulated]


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(_fields(a), _fields(b)))


def test_a_repeated_request_gives_a_fresh_evaluations_numbers():
    seconds = np.linspace(0.0, 86400.0 * 3, 41)
    first = ts.time_scales(EPOCH, seconds)
    for _ in range(2):
        assert _same(ts.time_scales(EPOCH, seconds), ts._time_scales(EPOCH, seconds))
    assert _same(first, ts._time_scales(EPOCH, seconds))


def test_other_times_are_not_answered_from_the_kept_ones():
    seconds = np.linspace(0.0, 86400.0, 5)
    ts.time_scales(EPOCH, seconds)
    assert _same(ts.time_scales(EPOCH, seconds + 1.0), ts._time_scales(EPOCH, seconds + 1.0))
    assert _same(ts.time_scales("2025-03-02T00:00:00Z", seconds), ts._time_scales("2025-03-02T00:00:00Z", seconds))


def test_changing_a_returned_array_leaves_the_next_answer():
    seconds = np.array([10.0, 20.0])
    ts.time_scales(EPOCH, seconds)
    got = ts.time_scales(EPOCH, seconds)                  # from the kept ones
    for arr in _fields(got):
        arr[...] = 0
    assert _same(ts.time_scales(EPOCH, seconds), ts._time_scales(EPOCH, seconds))


def test_another_earth_orientation_table_is_not_answered_from_the_kept_ones():
    seconds = np.array([0.0, 3600.0])
    default = ts.time_scales(EPOCH, seconds)
    shifted = iers.earth_orientation_table.get().copy()
    shifted["UT1_UTC"] = shifted["UT1_UTC"] + 0.25 * shifted["UT1_UTC"].unit
    with iers.earth_orientation_table.set(shifted):
        other = ts.time_scales(EPOCH, seconds)
    np.testing.assert_allclose(other.orientation.ut1_minus_utc - default.orientation.ut1_minus_utc, 0.25, atol=1e-12)
    assert _same(ts.time_scales(EPOCH, seconds), default)


def test_bad_input_is_refused_as_before():
    import pytest

    with pytest.raises(ValueError, match="epoch must be an ISO-8601"):
        ts.time_scales(["not", "a", "time"], 0.0)
    with pytest.raises(ValueError, match="NaN or infinity"):
        ts.time_scales(EPOCH, [np.nan])
