"""Compilation is timed apart from a run's wall time (numba's compile events, any thread)."""
from __future__ import annotations

import threading

from cistrack.runs.compile_clock import CompileClock


def _fresh_function():
    from numba import njit

    @njit(cache=False)
    def f(x):
        return x * 2.0 + 1.0

    return f


def test_compiling_inside_the_clock_is_counted():
    f = _fresh_function()
    with CompileClock() as clock:
        f(1.0)
    assert clock.seconds > 0.0


def test_calling_compiled_code_is_not_counted():
    f = _fresh_function()
    f(1.0)
    with CompileClock() as clock:
        for _ in range(1000):
            f(2.0)
    assert clock.seconds == 0.0


def test_compiling_in_another_thread_is_counted():
    f = _fresh_function()
    with CompileClock() as clock:
        t = threading.Thread(target=f, args=(3.0,))
        t.start()
        t.join()
    assert clock.seconds > 0.0


def test_a_run_reports_its_compile_time_apart():
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    s = run_scenario(load_scenario("quick").with_overrides({"duration_days": 1.4}), seed=1).summary
    assert s.compile_time_s >= 0.0 and s.wall_time_s > 0.0
    assert "compile_time_s" in s.to_dict()
