"""What observers are handed of a belief: views of the filter's arrays that refuse writes, made
without copying the particles, while the filter keeps its own arrays writeable."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud


def _belief() -> Belief:
    rng = np.random.default_rng(0)
    gm = GaussianMixture(np.array([0.4, 0.6]), rng.normal(size=(2, 6)), np.stack([np.eye(6)] * 2))
    return Belief(0.5, gm, ParticleCloud(rng.normal(size=(50, 6)), 0.5, np.full(50, 0.02), np.zeros(50, int)))


def test_a_read_only_belief_refuses_writes_into_each_of_its_arrays():
    ro = _belief().read_only()
    for a in (ro.mixture.weights, ro.mixture.means, ro.mixture.covariances, ro.samples.states, ro.samples.weights,
              ro.samples.labels):
        with pytest.raises(ValueError, match="read-only"):
            a[...] = 0


def test_a_read_only_belief_shares_the_data_and_leaves_the_originals_writeable():
    b = _belief()
    ro = b.read_only()
    assert np.shares_memory(ro.samples.states, b.samples.states) and np.shares_memory(ro.mixture.means, b.mixture.means)
    assert b.samples.states.flags.writeable and b.mixture.covariances.flags.writeable
    assert ro.epoch == b.epoch and ro.samples.epoch == b.samples.epoch
