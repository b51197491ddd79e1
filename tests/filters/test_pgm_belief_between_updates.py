"""Between updates the PGM's belief is its propagated mixture: every particle keeps the component
it was drawn from, and each component is the mean and covariance of its particles now. Reading
the belief draws nothing from the filter's update stream, so the estimates do not depend on how
often a run reports it (its output cadence)."""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.random_streams import independent_stream

from .linear_models import LinearDynamics, LinearSensor, transition

M0 = np.array([1.0, 2.0, -0.5, 0.1, -0.1, 0.05])
P0 = np.diag([0.5, 0.5, 0.5, 0.05, 0.05, 0.05])
TIMES = np.array([0.5, 1.0, 1.5, 2.0])


def _measurements(sensor):
    return sensor.simulate(np.stack([transition(t) @ M0 for t in TIMES]), TIMES, np.random.default_rng(42))


def _started(sensor, dynamics=None, seed: int = 7) -> PGMFilter:
    filt = PGMFilter(n_particles=3000, n_components=4, reanchor="off")
    cloud = np.random.default_rng(3).multivariate_normal(M0, P0, 3000)
    filt.initialize(ParticleCloud(cloud, 0.0), dynamics or LinearDynamics(), sensor, np.random.default_rng(seed))
    return filt


def _track(filt, measurements, read_every_step: bool) -> list[np.ndarray]:
    """The particles after each update, predicted through two times between updates, at which
    the belief is read (or not)."""
    after = []
    t = 0.0
    for meas in measurements:
        for tt in np.linspace(t, meas.t, 4)[1:-1]:
            filt.predict(tt)
            if read_every_step:
                _ = filt.belief.mixture
        filt.predict(meas.t)
        filt.update(meas)
        after.append(filt.belief.samples.states.copy())
        t = meas.t
    return after


def test_reading_the_pgm_belief_between_updates_changes_none_of_its_estimates():
    sensor = LinearSensor(sigma=0.2, coords=(0, 1, 2))
    ms = _measurements(sensor)
    quiet = _track(_started(sensor), ms, read_every_step=False)
    watched = _track(_started(sensor), ms, read_every_step=True)
    for a, b in zip(quiet, watched):
        assert np.array_equal(a, b)


def test_between_updates_each_component_is_the_moments_of_the_particles_drawn_from_it():
    sensor = LinearSensor(sigma=0.2, coords=(0, 1, 2))
    filt = _started(sensor)
    meas = _measurements(sensor)[0]
    filt.predict(meas.t)
    filt.update(meas)
    drawn = filt.belief.samples.labels.copy()
    filt.predict(meas.t + 0.3)
    belief = filt.belief
    x = belief.samples.states
    assert np.array_equal(belief.samples.labels, drawn)
    for j in range(belief.mixture.n_components):
        mine = x[drawn == j]
        assert np.allclose(belief.mixture.means[j], mine.mean(axis=0), rtol=0, atol=1e-12)
        assert np.allclose(belief.mixture.covariances[j], np.cov(mine.T), rtol=1e-9, atol=1e-12)
        assert belief.mixture.weights[j] == mine.shape[0] / x.shape[0]


def test_particles_stopped_by_a_body_leave_their_components_with_them():
    sensor = LinearSensor(sigma=0.2, coords=(0, 1, 2))
    filt = _started(sensor, LinearDynamics(body_radius=1.96, body_x=1.2))
    meas = _measurements(sensor)[0]
    filt.predict(meas.t)
    filt.update(meas)
    drawn = filt.belief.samples.labels.copy()
    n_before = drawn.size
    filt.predict(meas.t + 0.5)
    belief = filt.belief
    assert len(belief.samples) < n_before  # some particles hit the body
    assert belief.samples.labels.shape == (len(belief.samples),)
    assert np.isclose(belief.mixture.weights.sum(), 1.0)


def test_the_belief_stream_leaves_the_filters_own_draws_unchanged():
    plain = np.random.default_rng(11).random(5)
    rng = np.random.default_rng(11)
    child = independent_stream(rng)
    assert np.array_equal(rng.random(5), plain)
    assert not np.array_equal(child.random(5), plain)


def test_a_generator_without_a_seed_sequence_still_gets_a_stream_of_its_own():
    bare = np.random.Generator(np.random.RandomState(5)._bit_generator)  # legacy seeding: no seed sequence
    child = independent_stream(bare)
    assert isinstance(child, np.random.Generator)
    assert child.random() != bare.random()
