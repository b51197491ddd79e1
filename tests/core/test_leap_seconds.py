"""UTC labels and elapsed time: t is elapsed SI seconds since the epoch (as the sensor, Earth
orientation and ephemeris evaluate it, :mod:`cistrack.astro.timescales`), so a label after a leap
second lying between the epoch and it is one second more elapsed time than the clock difference;
with no leap second in between, the conversions are the clock arithmetic bit for bit."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone

import numpy as np
import pytest

from cistrack import units
from cistrack.astro import timescales
from cistrack.fitting.arcs import in_time_base
from cistrack.fitting.fit_export import fit_grid
from cistrack.model.measurement import MeasurementSet
from cistrack.units import TU_S, parse_utc, tu_to_utc, utc_to_tu

BEFORE = parse_utc("2016-12-31T23:00:00Z")   # the leap second 2016-12-31T23:59:60 lies 1 h later
AFTER = parse_utc("2017-01-01T01:00:00Z")
LABELS = ["2016-12-31T23:30:00Z", "2016-12-31T23:59:59.999999Z", "2017-01-01T00:00:00Z",
          "2017-01-01T00:05:00.123456Z", "2017-01-02T12:00:00Z"]


def _clock_tu(epoch: datetime, when: datetime) -> float:
    return (when - epoch).total_seconds() / TU_S


def test_a_label_after_a_leap_second_is_one_second_more_elapsed_time_than_the_clock_difference():
    early, late = parse_utc("2016-12-31T23:30:00Z"), parse_utc("2017-01-01T00:05:00Z")
    assert utc_to_tu(BEFORE, early) * TU_S == pytest.approx(1800.0, abs=1e-6)
    assert utc_to_tu(BEFORE, late) * TU_S == pytest.approx(3901.0, abs=1e-6)
    assert utc_to_tu(AFTER, early) * TU_S == pytest.approx(-5401.0, abs=1e-6)     # backwards across it too
    assert units.leap_seconds(parse_utc("2000-01-01T00:00:00Z"), parse_utc("2025-01-01T00:00:00Z")) == 5.0


@pytest.mark.parametrize("epoch", [BEFORE, AFTER, parse_utc("2016-06-30T00:00:00Z")])
@pytest.mark.parametrize("label", LABELS)
def test_a_label_round_trips_through_elapsed_time_across_the_leap_second(epoch, label):
    when = parse_utc(label)
    assert tu_to_utc(epoch, utc_to_tu(epoch, when)) == when


@pytest.mark.parametrize("label", LABELS)
def test_elapsed_time_is_what_the_time_scales_evaluate_at_the_label(label):
    when = parse_utc(label)
    seconds = units.elapsed_seconds(BEFORE, when)
    assert timescales.utc_time(BEFORE, seconds).isot[:23] == units.format_utc(when)[:23]    # to the millisecond


def test_the_last_leap_second_cistrack_knows_without_erfa_is_the_last_of_erfas_table():
    import erfa

    year, month, _ = erfa.leap_seconds.get()[-1]
    assert datetime(int(year), int(month), 1, tzinfo=timezone.utc) == units.LAST_LEAP_SECOND_END
    assert units.leap_seconds(parse_utc("2016-12-31T00:00:00Z"), units.LAST_LEAP_SECOND_END) == 1.0


def test_with_no_leap_second_in_between_the_conversions_are_the_clock_arithmetic_bit_for_bit():
    rng = np.random.default_rng(5)
    epoch = parse_utc("2025-01-10T03:17:00.25Z")
    for s in rng.uniform(-3e7, 3e7, 200):
        when = epoch + timedelta(seconds=float(s))
        assert utc_to_tu(epoch, when) == (when - epoch).total_seconds() / TU_S
        t = float(s) / TU_S
        assert tu_to_utc(epoch, t) == epoch + timedelta(seconds=t * TU_S)


def test_an_instant_inside_a_leap_second_is_labelled_the_last_microsecond_before_it():
    inside = [3600.0, 3600.5, 3600.999]       # 23:59:60.0 to 23:59:60.999 after BEFORE
    expected = datetime(2016, 12, 31, 23, 59, 59, 999999, tzinfo=timezone.utc)
    assert [units.utc_after(BEFORE, s) for s in inside] == [expected] * 3
    assert units.utc_after(BEFORE, 3601.0) == parse_utc("2017-01-01T00:00:00Z")
    assert units.utc_after(AFTER, -3600.5) == expected                        # and coming from after it


def test_a_time_grid_across_the_leap_second_keeps_whole_minute_labels():
    first, last = utc_to_tu(BEFORE, parse_utc("2016-12-31T23:50:00Z")), utc_to_tu(BEFORE, AFTER)
    grid, n_arc = fit_grid(first, last, BEFORE, minutes=10.0)
    labels = [units.format_utc(tu_to_utc(BEFORE, t))[:19] for t in grid]
    assert labels[:3] == ["2016-12-31T23:50:00", "2017-01-01T00:00:00", "2017-01-01T00:10:00"]
    assert np.diff(grid)[:2] * TU_S == pytest.approx([601.0, 600.0], abs=1e-6)


def _set(times) -> MeasurementSet:
    n = len(times)
    return MeasurementSet(np.asarray(times, dtype=float), np.zeros((n, 2)), np.ones((n, 2)), ("ra", "dec"))


def test_moving_read_times_to_an_epoch_after_the_leap_second_counts_it_only_where_it_lies_between():
    read = parse_utc("2000-01-01T00:00:00Z")
    labels = [parse_utc(x) for x in LABELS]
    moved = in_time_base(_set([utc_to_tu(read, w) for w in labels]), read, BEFORE).times
    np.testing.assert_allclose(moved * TU_S, [units.elapsed_seconds(BEFORE, w) for w in labels], atol=1e-6)
    # before the leap second: the clock arithmetic of the read times, bit for bit
    assert moved[0] == _clock_tu(read, labels[0]) - _clock_tu(read, BEFORE)
