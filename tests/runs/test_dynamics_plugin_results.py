"""A third party's dynamics whose ``propagate`` raises, calls sys.exit, or returns a Propagation
that breaks its contract (NaN states, states of 5 components, ``alive`` of the wrong shape, other
output times) ends the run "failed" naming the dynamics and its distribution: it had been blamed
on the filter, on a metric stage or on the orbit ("every particle hit a body"), or, for wrong
output times, accepted."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.interfaces.dynamics import Dynamics, Propagation
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

GOOD_CALLS = 3
"""Calls of ``propagate`` answered right before the test dynamics breaks (the truth's and the IOD's)."""


class HDynamics(Dynamics):
    """The built-in cr3bp, broken by ``how`` after :data:`GOOD_CALLS` calls of propagate."""

    def __init__(self, how: str = "ok") -> None:
        self.how = how
        self._base = load_registry(autoload_third_party=False).create("dynamics", "cr3bp")
        self._calls = 0

    @property
    def primaries(self):
        return self._base.primaries

    def derivatives(self, t, states):
        return self._base.derivatives(t, states)

    def propagate(self, states, t0, times):
        self._calls += 1
        p = self._base.propagate(states, t0, times)
        if self._calls <= GOOD_CALLS or self.how == "ok":
            return p
        if self.how == "raise":
            raise ZeroDivisionError("propagate broke")
        if self.how == "exit":
            raise SystemExit(7)
        states, alive, times = p.states, p.alive, p.times
        states = {"nan": states * np.nan, "width": states[..., :5]}.get(self.how, states)
        alive = alive[:1] if self.how == "alive" else alive
        times = times[::-1] + 1.0 if self.how == "times" else times
        return Propagation(times, states, alive, p.impact_body, p.impact_time)


def _run(how: str):
    reg = load_registry(autoload_third_party=False)
    reg.add("dynamics", "h-dyn", HDynamics, "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg, overrides={"duration_days": 1.4, "dynamics": {"name": "h-dyn", "how": how}})
    return run_scenario(scen, seed=1, registry=reg).summary


def test_a_dynamics_plugin_that_keeps_its_contract_runs_to_the_end():
    assert _run("ok").status == "finished"


@pytest.mark.parametrize("how, what", [
    ("raise", "raised ZeroDivisionError: propagate broke"),
    ("exit", "raised SystemExit: it called sys.exit(7)"),
    ("nan", "returned NaN or infinite states for "),
    ("width", "returned states of shape ("),
    ("alive", "returned alive of shape (1,), expected ("),
    ("times", "returned times ["),
])
def test_a_dynamics_plugin_breaking_its_contract_fails_the_run_naming_it(how, what):
    summary = _run(how)
    assert summary.status == "failed"  # not "filter-failed": the filter is not at fault
    assert summary.failure.startswith(f"dynamics 'h-dyn' (hplug 0.1): propagate() {what}"), summary.failure
