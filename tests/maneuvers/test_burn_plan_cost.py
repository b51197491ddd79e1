"""Resolving a plan of many burns flies the truth once from burn to burn (probe J3): each burn
had been flown from the start through all the earlier ones, so 1,000 burns took 36 s and 10,000
over 5 minutes before a run's first step."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.plugins.maneuvers.plans import BurnsPlan

NRHO = np.array([1.0221, 0.0, -0.1821508, 0.0, -0.10342725, 0.0])


class CountingDynamics:
    """The registry's cr3bp model, counting the propagations asked of it."""

    def __init__(self, dynamics) -> None:
        self.dynamics, self.propagations = dynamics, 0

    def __getattr__(self, name):
        return getattr(self.dynamics, name)

    def propagate(self, *args, **kwargs):
        self.propagations += 1
        return self.dynamics.propagate(*args, **kwargs)


def _propagations_for(registry, n_burns: int) -> int:
    dynamics = CountingDynamics(registry.create("dynamics", "cr3bp"))
    plan = BurnsPlan([{"t_days": float(t), "delta_v_ms": 0.001} for t in np.linspace(0.01, 2.0, n_burns)])
    assert len(plan.impulses(dynamics, NRHO, 0.0, float(units.days_to_tu(3.0)))) == n_burns
    return dynamics.propagations


@pytest.mark.parametrize("n_burns", [10, 40])
def test_each_burn_costs_one_propagation_from_the_burn_before_it(registry, n_burns):
    assert _propagations_for(registry, n_burns) == n_burns
