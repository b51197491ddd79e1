"""The PGM carries each particle's integration step from one prediction to the next: survivors
keep their own, particles drawn from a cluster's posterior start with their cluster's."""
from __future__ import annotations

import numpy as np

from cistrack.plugin.registry import Registry
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.filters.ensemble_propagation import steps_by_group
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


def test_each_group_gets_the_lower_quartile_of_its_particles_steps():
    steps = np.array([4.0, 1.0, 3.0, 2.0, 5.0, 10.0, 30.0, 20.0])
    labels = np.array([0, 0, 0, 0, 0, 2, 2, 2])
    got = steps_by_group(steps, labels, 4)
    assert got.tolist() == [2.0, 0.0, 10.0, 0.0]  # empty groups: 0, the integrator chooses


def test_no_group_steps_without_carried_steps():
    assert steps_by_group(None, np.zeros(3, dtype=int), 1) is None


class _RecordingCR3BP(CR3BP):
    """The CR3BP, noting how many particles of each filter prediction came with a carried step."""

    calls: list[tuple[int, int]] = []

    def propagate(self, states, t0, times, *, rtol=None, atol=None, steps=None):
        n = np.shape(states)[0]
        if n >= 100:  # the filter's cloud, not the truth or the IOD
            type(self).calls.append((n, 0 if steps is None else int(np.count_nonzero(np.asarray(steps) > 0))))
        return super().propagate(states, t0, times, rtol=rtol, atol=atol, steps=steps)


def test_the_pgm_starts_every_prediction_after_the_first_with_carried_steps():
    reg = Registry().load_entry_points()
    reg.add("dynamics", "recording-cr3bp", _RecordingCR3BP)
    _RecordingCR3BP.calls = []
    scen = load_scenario("quick", reg, overrides={
        "dynamics": {"name": "recording-cr3bp"}, "duration_days": 1.5,
        "filter": {"n_particles": 2000}, "iod": {"n_particles": 2000}})
    result = run_scenario(scen, seed=3, registry=reg)
    assert result.summary.status == "finished"
    calls = _RecordingCR3BP.calls
    assert len(calls) >= 4 and calls[0][1] == 0  # the IOD cloud has no steps yet
    assert all(carried == n for n, carried in calls[1:]), calls


class _OldStyleCR3BP(CR3BP):
    """A model written before step carrying: it overrides propagate without ``steps``."""

    def propagate(self, states, t0, times, *, rtol=None, atol=None):
        return super().propagate(states, t0, times, rtol=rtol, atol=atol)


def test_a_model_whose_propagate_takes_no_steps_is_propagated_as_before():
    from cistrack.plugins.filters.ensemble_propagation import carries_steps, propagate_ensemble

    dyn = _OldStyleCR3BP()
    x = CR3BP().propagate(np.tile(np.r_[1.0221, 0.0, -0.1821508, 0.0, -0.10342725, 0.0], (5, 1)), 0.0, 0.0).final
    assert not carries_steps(dyn) and carries_steps(CR3BP())
    final, alive, steps = propagate_ensemble(dyn, x, 0.0, 0.1, "pgm", steps=np.full(5, 0.01))
    assert alive.all() and steps is None
