"""Conformance checks for Schedule plugins (three 12-hour passes, one a day)."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.schedule import Schedule
from cistrack.testing.check_support import no_global_random_state, require, round_trip, unchanged
from cistrack.testing.fixtures import sample_passes

__all__ = ["SCHEDULE_CHECKS"]


def _plan(schedule, passes, t_end, seed=0) -> np.ndarray:
    t = np.asarray(schedule.plan(passes, t_end, np.random.default_rng(seed)))
    require(t.ndim == 1 and (t.size == 0 or np.issubdtype(t.dtype, np.floating)),
            f"plan() returned {t.dtype} shape {t.shape}, expected a (J,) float array")
    return t


def check_is_schedule(schedule) -> None:
    require(isinstance(schedule, Schedule), f"{type(schedule).__name__} does not derive from cistrack.interfaces.Schedule")


def check_plan_times_inside_passes(schedule) -> None:
    """Times strictly increase, each lies inside a pass, none after t_end."""
    passes = sample_passes()
    for t_end in (passes[-1].end, 0.5 * (passes[0].end + passes[1].start), passes[1].start + 0.3 * passes[1].duration):
        t = _plan(schedule, passes, t_end)
        require(np.all(np.isfinite(t)), "plan() returned NaN or infinite times")
        require(np.all(np.diff(t) > 0), "plan() times do not increase strictly")
        require(np.all(t <= t_end + 1e-12), f"plan() returned times after t_end = {t_end:.4g} TU")
        inside = np.zeros(t.shape, dtype=bool)
        for p in passes:
            inside |= (t >= p.start - 1e-12) & (t <= p.end + 1e-12)
        require(np.all(inside), f"plan() returned times outside every pass: {t[~inside][:3]}")
    require(_plan(schedule, passes, passes[-1].end).size > 0, "plan() returned no times for three 12-hour passes")


def check_no_passes_no_times(schedule) -> None:
    t = _plan(schedule, [], 10.0)
    require(t.size == 0, f"plan() with no visibility passes returned {t.size} times")


def check_plan_reproducible(schedule) -> None:
    passes = sample_passes()
    with no_global_random_state("plan()"), unchanged(passes=passes):
        a = _plan(schedule, passes, passes[-1].end, seed=3)
    b = _plan(schedule, passes, passes[-1].end, seed=3)
    require(np.array_equal(a, b), "plan() with generators of the same seed gave different times")


def check_same_after_pickle(schedule) -> None:
    passes = sample_passes()
    other = round_trip(schedule)
    require(np.array_equal(_plan(schedule, passes, passes[-1].end, 5), _plan(other, passes, passes[-1].end, 5)),
            "the unpickled copy plans different times")


SCHEDULE_CHECKS = [
    ("is_schedule", check_is_schedule),
    ("plan_times_inside_passes", check_plan_times_inside_passes),
    ("no_passes_no_times", check_no_passes_no_times),
    ("plan_reproducible", check_plan_reproducible),
    ("same_after_pickle", check_same_after_pickle),
]
