"""Tasking schedules: the general phased policy, its presets and the paper's three scenarios."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.interfaces import Pass
from cistrack.plugins.sensors.schedules import (
    EverySchedule, PaperExample1Schedule, PaperExample2Schedule, PaperExample3Schedule, PhasedSchedule,
    RandomConsecutiveSchedule,
)
from cistrack.plugin.registry import load_registry
from cistrack.units import TU_S

HOUR = 3600.0 / TU_S
MINUTE = 60.0 / TU_S
DAY = 86400.0 / TU_S
PASS_HOURS = 12.0
PERIOD_HOURS = 24.84          # a target near the Moon rises ~50 min later every day
FIRST_HOURS = 2.0


def synthetic_passes(days: float) -> list[Pass]:
    """12-hour passes every 24.84 h, the first starting 2 h after the epoch."""
    starts = np.arange(FIRST_HOURS, days * 24.0, PERIOD_HOURS) * HOUR
    return [Pass(float(s), float(s + PASS_HOURS * HOUR)) for s in starts]


def pass_index(passes, times) -> np.ndarray:
    """Index of the pass containing each time (-1 when none)."""
    out = np.full(len(times), -1)
    for i, p in enumerate(passes):
        out[(times >= p.start - 1e-12) & (times <= p.end + 1e-12)] = i
    return out


def check_contract(times, passes, t_end):
    assert np.all(np.diff(times) > 0)
    assert np.all(pass_index(passes, times) >= 0)
    assert np.all(times <= t_end)


def test_all_names_are_registered_as_schedules():
    reg = load_registry()
    for name in ("every", "random-consecutive", "phased", "paper-example-1", "paper-example-2",
                 "paper-example-3"):
        assert reg.create("schedule", name) is not None


def test_every_40_minutes_gives_19_measurements_per_12_hour_pass():
    passes = synthetic_passes(5)
    t = EverySchedule(interval_minutes=40.0).plan(passes, 5 * DAY, np.random.default_rng(0))
    check_contract(t, passes, 5 * DAY)
    idx = pass_index(passes, t)
    assert np.all(np.bincount(idx) == 19)
    assert np.allclose(np.diff(t)[np.diff(idx) == 0], 40 * MINUTE)
    assert np.isclose(t[0], passes[0].start)


def test_nothing_is_planned_after_t_end():
    passes = synthetic_passes(5)
    t_end = passes[1].start + 3 * HOUR
    t = EverySchedule().plan(passes, t_end, np.random.default_rng(0))
    check_contract(t, passes, t_end)
    assert np.sum(pass_index(passes, t) == 1) == 5          # 0, 40, ..., 160 min


def test_no_passes_means_no_measurements():
    assert EverySchedule().plan([], 10.0, np.random.default_rng(0)).size == 0


def test_random_consecutive_takes_k_consecutive_measurements_in_each_pass():
    passes = synthetic_passes(10)
    t = RandomConsecutiveSchedule(count=5).plan(passes, 10 * DAY, np.random.default_rng(4))
    check_contract(t, passes, 10 * DAY)
    idx = pass_index(passes, t)
    assert np.all(np.bincount(idx) == 5)
    gaps = np.diff(t)[np.diff(idx) == 0] / MINUTE
    assert np.all((gaps >= 40 - 1e-6) & (gaps <= 60 + 1e-6))
    offsets = np.array([t[idx == i][0] - p.start for i, p in enumerate(passes)]) / HOUR
    assert offsets.std() > 0.5                                 # placed at random, not at the start


def test_random_consecutive_in_a_short_pass_takes_as_many_as_fit():
    short = [Pass(0.0, 100 * MINUTE)]
    t = RandomConsecutiveSchedule(count=5, interval_minutes=40.0, interval_max_minutes=40.0).plan(
        short, 1.0, np.random.default_rng(0))
    assert np.allclose(t / MINUTE, [0, 40, 80])


def test_schedules_are_reproducible_from_the_generator():
    passes = synthetic_passes(10)
    s = PaperExample1Schedule()
    a = s.plan(passes, 10 * DAY, np.random.default_rng(11))
    b = s.plan(passes, 10 * DAY, np.random.default_rng(11))
    c = s.plan(passes, 10 * DAY, np.random.default_rng(12))
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_paper_example_1_whole_first_pass_then_5_consecutive_per_pass():
    passes = synthetic_passes(7)
    t = PaperExample1Schedule().plan(passes, 7 * DAY, np.random.default_rng(1))
    check_contract(t, passes, 7 * DAY)
    idx = pass_index(passes, t)
    counts = np.bincount(idx, minlength=len(passes))
    first = t[idx == 0]
    gaps = np.diff(first) / MINUTE
    assert np.all((gaps >= 40 - 1e-6) & (gaps <= 60 + 1e-6))
    assert np.isclose(first[0], passes[0].start)
    assert passes[0].end - first[-1] < 60 * MINUTE             # covers the whole pass
    assert 13 <= counts[0] <= 19                                # 12 h at 40-60 min spacing
    assert np.all(counts[1:] == 5)


def test_paper_example_2_counts_and_ten_day_gap():
    passes = synthetic_passes(30)
    t = PaperExample2Schedule().plan(passes, 30 * DAY, np.random.default_rng(0))
    check_contract(t, passes, 30 * DAY)
    origin = passes[0].start
    early = t[t <= origin + 33 * HOUR]
    late = t[t > origin + 33 * HOUR]
    # pass 0 (12 h): 19 at 40 min; pass 1 starts 24.84 h after, cut at 33 h: 8.16 h -> 13
    assert early.size == 19 + 13
    assert late[0] - early[-1] >= 10 * DAY
    assert late[0] >= origin + 33 * HOUR + 10 * DAY
    steps = np.diff(late) / (16 * HOUR)
    assert np.allclose(steps, np.round(steps)) and np.all(steps >= 1 - 1e-9)
    # an independent count: 16-hour grid points from the resume time that fall in a pass
    grid = origin + (33 + 240) * HOUR + np.arange(0, 10_000) * 16 * HOUR
    grid = grid[grid <= passes[-1].end]
    assert late.size == int(np.sum(pass_index(passes, grid) >= 0))


def test_paper_example_3_counts_and_150_day_gap():
    passes = synthetic_passes(160)
    t = PaperExample3Schedule().plan(passes, 160 * DAY, np.random.default_rng(0))
    check_contract(t, passes, 160 * DAY)
    origin = passes[0].start
    early = t[t <= origin + 24 * HOUR]
    late = t[t > origin + 24 * HOUR]
    assert early.size == 19                    # the second pass starts after 24 h
    assert late[0] - early[-1] >= 150 * DAY
    idx = pass_index(passes, late)
    counts = np.bincount(idx)[idx.min():]
    assert np.all(counts[1:] == 19)            # the first resumed pass may be cut by the window
    assert 1 <= counts[0] <= 19


def test_phased_schedule_with_explicit_shutoff_and_fixed_cadence_after_a_date():
    passes = synthetic_passes(20)
    s = PhasedSchedule(origin="epoch", phases=[
        {"rule": "every", "interval_minutes": 60.0, "end_days": 2},
        {"rule": "off", "start_days": 2, "end_days": 10},
        {"rule": "every", "interval_minutes": 120.0, "start_days": 10},
    ])
    t = s.plan(passes, 20 * DAY, np.random.default_rng(0))
    check_contract(t, passes, 20 * DAY)
    assert not np.any((t > 2 * DAY) & (t < 10 * DAY))
    late = t[t >= 10 * DAY]
    idx = pass_index(passes, late)
    assert np.allclose(np.diff(late)[np.diff(idx) == 0], 120 * MINUTE)


def test_schedules_pickle_and_report_their_parameters():
    s = PaperExample2Schedule(shutoff_days=5.0)
    s2 = pickle.loads(pickle.dumps(s))
    assert s2.get_params() == s.get_params()
    assert s.get_params()["shutoff_days"] == 5.0


@pytest.mark.parametrize("phases", [
    [],
    [{"rule": "sometimes", "interval_minutes": 40}],
    [{"rule": "every"}],
    [{"rule": "every", "interval_minutes": -4}],
    [{"rule": "every", "interval_minutes": 40, "start_hours": 1, "start_days": 1}],
    [{"rule": "every", "interval_minutes": 40, "frequency": 3}],
    [{"rule": "every", "interval_minutes": 40, "interval_max_minutes": 30}],
    [{"rule": "every", "interval_minutes": 40, "start_hours": 5, "end_hours": 4}],
    ["every"],
])
def test_invalid_phases_raise_parameter_error(phases):
    with pytest.raises(ParameterError):
        PhasedSchedule(phases=phases)


def test_presets_on_a_real_nrho_geometry_stay_inside_the_elevation_mask(telescope, nrho_arc):
    times, states = nrho_arc
    passes = telescope.passes(times, states)
    for s in (EverySchedule(), PaperExample1Schedule(), PaperExample2Schedule()):
        t = s.plan(passes, times[-1], np.random.default_rng(5))
        assert t.size > 10
        x = np.column_stack([np.interp(t, times, states[:, k]) for k in range(6)])
        el = telescope.measure(x, t)[:, 1]
        assert np.all(el >= np.radians(10.0) - 1e-5)
