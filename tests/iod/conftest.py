"""Fixtures for the IOD tests: the 9:2 NRHO truth, the default telescope and the default
schedule ("paper-example-1": the first pass every 40-60 min, then 5 consecutive per pass),
planned once with a fixed seed.

The truth is integrated here with scipy (REFERENCE.md's approximate 9:2 state, rtol 1e-12) until
the orbit catalog ("nrho-9-2") lands; the IOD only needs a smooth CR3BP arc over ~2 days."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.plugins.sensors.schedules import PaperExample1Schedule
from cistrack.units import hours_to_tu

from reference_cr3bp import cr3bp_rhs  # noqa: E402  (tests/ is on sys.path)
NRHO_9_2 = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])


@dataclass
class Scenario:
    truth: object          # callable t (TU) -> (6,) or (6, K) truth state(s)
    sensor: GroundTelescope
    times: np.ndarray      # (K,) measurement times, TU (first pass and the start of the second)

    def truth_states(self, t) -> np.ndarray:
        return np.asarray(self.truth(np.asarray(t, dtype=float))).T

    def simulate(self, rng: np.random.Generator):
        return self.sensor.simulate(self.truth_states(self.times), self.times, rng)


@pytest.fixture(scope="session")
def truth():
    """Dense-output truth of the approximate 9:2 NRHO over 3 days (rtol 1e-12)."""
    t_end = 3 * 86400.0 / 375149.0
    sol = solve_ivp(cr3bp_rhs, (0.0, t_end), NRHO_9_2, rtol=1e-12, atol=1e-13, method="DOP853",
                    dense_output=True)
    return sol.sol


def make_scenario(truth, sensor: GroundTelescope) -> Scenario:
    t_end = 3 * 86400.0 / 375149.0
    grid = np.arange(0.0, t_end, hours_to_tu(1.0 / 6.0))
    # a pass already under way at t = 0 is cut short: start tracking at the first full pass
    passes = [p for p in sensor.passes(grid, truth(grid).T) if p.start > 0.0]
    times = PaperExample1Schedule().plan(passes, t_end, np.random.default_rng(2025))
    return Scenario(truth, sensor, times)


@pytest.fixture(scope="session")
def scenario(truth) -> Scenario:
    """Default telescope measuring az/el and an IOD range (alpha = 0.05)."""
    return make_scenario(truth, GroundTelescope(measure_range=True, range_alpha=0.05))


@pytest.fixture(scope="session")
def angles_only_scenario(truth) -> Scenario:
    return make_scenario(truth, GroundTelescope())
