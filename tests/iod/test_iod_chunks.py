"""The kinematic IOD fits its Monte Carlo samples in chunks with the numbers of one whole draw
(issue 15: memory must not grow with the oversampling factor, and a fixed seed must give the same
cloud whatever the chunk size)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.iod.chunked_draws import draw_in_chunks
from cistrack.plugins.iod.kinematic import KinematicFitIOD
from cistrack.plugins.iod.kinematic_presets import (NoisyRangeIOD, UniformRangeIOD,
                                                    UniformRangeVelocityBoundIOD)
from cistrack.plugins.iod.range_priors import NoisyRange, UniformRange


def _angles(c, g):
    return g.standard_normal((c, 11, 2))


@pytest.mark.parametrize("prior", [UniformRange(), NoisyRange(0.1)], ids=["uniform", "noisy"])
@pytest.mark.parametrize("chunk", [1, 7, 100, 1000])
def test_chunks_concatenate_to_one_whole_draw_and_leave_the_generator_where_it_would(prior, chunk):
    measured = np.linspace(1.0, 1.2, 11)

    def ranges(c, g):
        return prior.draw(measured, (c, 11), g)

    whole = np.random.default_rng(42)
    want_angles, want_ranges = _angles(700, whole), ranges(700, whole)
    rng = np.random.default_rng(42)
    parts = list(draw_in_chunks(700, rng, _angles, ranges, chunk))
    assert len(parts) == -(-700 // chunk)
    assert np.array_equal(np.concatenate([a for a, _ in parts]), want_angles)
    assert np.array_equal(np.concatenate([r for _, r in parts]), want_ranges)
    assert rng.random() == whole.random()


def test_a_chunk_size_below_one_is_refused():
    with pytest.raises(ValueError, match="chunk must be >= 1"):
        list(draw_in_chunks(5, np.random.default_rng(0), _angles, _angles, 0))


@pytest.mark.parametrize("iod", [NoisyRangeIOD(n_particles=400), UniformRangeIOD(n_particles=400),
                                 UniformRangeVelocityBoundIOD(n_particles=400),
                                 KinematicFitIOD(n_particles=400, range_sampling="per-sample")],
                         ids=["noisy", "uniform", "velocity-bound", "per-sample"])
def test_the_cloud_does_not_depend_on_the_chunk_size(scenario, iod):
    ms = scenario.simulate(np.random.default_rng(5))
    rng_whole, rng_chunked = np.random.default_rng(11), np.random.default_rng(11)
    whole = iod.estimate(ms, scenario.sensor, rng_whole)
    iod._chunk = 97  # a batch of 2,000 samples in 21 chunks
    try:
        chunked = iod.estimate(ms, scenario.sensor, rng_chunked)
    finally:
        del iod._chunk
    assert np.array_equal(chunked.states, whole.states)
    assert chunked.meta == whole.meta
    assert rng_chunked.random() == rng_whole.random()  # the filter's draws after the IOD as well
