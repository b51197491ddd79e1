"""Guards against the PGM filter's known failure modes: tiny clusters, weight underflow,
angle wrap and particles lost to impacts. Each is handled without NaN."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import ParticleCloud
from cistrack.errors import FilterError, MeasurementError
from cistrack.model.measurement import Measurement
from cistrack.plugins.filters.pgm.cluster_merge import merge_small_clusters
from cistrack.plugins.filters.enkf import EnKFFilter
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.sir import SIRFilter
from cistrack.plugins.filters.ukf import UKFFilter

from .linear_models import BearingSensor, LinearDynamics, LinearSensor

FILTERS = {
    "pgm": lambda: PGMFilter(n_particles=3000, n_components=4),
    "ukf": lambda: UKFFilter(n_samples=500),
    "enkf": lambda: EnKFFilter(n_particles=1000),
    "sir": lambda: SIRFilter(n_particles=3000),
}


def gaussian_cloud(mean, sd, n=5000, seed=0):
    rng = np.random.default_rng(seed)
    return ParticleCloud(mean + sd * rng.standard_normal((n, 6)), 0.0)


def assert_finite_belief(belief):
    assert np.all(np.isfinite(belief.mixture.weights))
    assert np.all(np.isfinite(belief.mixture.means))
    assert np.all(np.isfinite(belief.mixture.covariances))
    assert np.all(np.isfinite(belief.samples.states))


def test_clusters_smaller_than_the_dimension_are_merged_into_the_nearest():
    rng = np.random.default_rng(1)
    x = np.vstack([rng.standard_normal((500, 6)), rng.standard_normal((500, 6)) + 10.0,
                   rng.standard_normal((3, 6)) + 9.0])
    labels = np.repeat([0, 1, 2], [500, 500, 3])
    new, merged = merge_small_clusters(x, labels, 12)
    assert merged == 1
    assert new.max() == 1
    assert np.all(new[-3:] == new[600])


def test_pgm_update_with_a_cluster_of_fewer_particles_than_the_dimension_stays_finite():
    rng = np.random.default_rng(2)
    x = np.vstack([rng.normal(0.0, 0.1, (2000, 6)), rng.normal(50.0, 0.1, (3, 6))])  # 3 far outliers
    sensor = LinearSensor(sigma=0.1)
    filt = PGMFilter(n_particles=2003, n_components=2)
    filt.initialize(ParticleCloud(x, 0.0), LinearDynamics(), sensor, rng)
    filt.update(Measurement(0.0, np.array([0.05, 0.0]), 0.01 * np.eye(2), sensor.names))
    assert filt.diagnostics["clusters_merged"] >= 1
    assert_finite_belief(filt.belief)


def test_duplicate_particles_give_a_finite_positive_definite_mixture():
    x = np.repeat(np.arange(6.0)[None], 200, axis=0)
    filt = PGMFilter(n_particles=200, n_components=3)
    filt.initialize(ParticleCloud(x, 0.0), LinearDynamics(), LinearSensor(), np.random.default_rng(0))
    mix = filt.belief.mixture
    assert np.all(np.linalg.eigvalsh(mix.covariances) > 0)


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_a_measurement_far_from_every_particle_underflows_no_weight_to_nan(name):
    sensor = LinearSensor(sigma=1e-4)
    filt = FILTERS[name]()
    filt.initialize(gaussian_cloud(np.zeros(6), 0.01), LinearDynamics(), sensor, np.random.default_rng(0))
    # 1e4 sigma of the cloud and 1e6 sigma of the noise away: every linear-domain weight is 0
    filt.update(Measurement(0.0, np.array([100.0, -100.0]), 1e-8 * np.eye(2), sensor.names))
    assert_finite_belief(filt.belief)


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_azimuth_just_below_two_pi_is_an_update_near_zero(name):
    # particles on both sides of azimuth 0 (y ~ 0, x ~ 1); measurement at 359.999 deg
    sensor = BearingSensor(sigma=1e-4)
    mean = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    az = np.deg2rad(359.999)
    results = []
    for z_az in (az, az - 2 * np.pi):
        filt = FILTERS[name]()
        filt.initialize(gaussian_cloud(mean, 0.002, seed=4), LinearDynamics(), sensor, np.random.default_rng(9))
        filt.update(Measurement(0.0, np.array([z_az, 0.0]), 1e-8 * np.eye(2), sensor.names))
        b = filt.belief
        assert_finite_belief(b)
        results.append(b.mixture.mean)
    # the posterior moves to y = tan(-0.001 deg) ~ -1.75e-5, and equally for either spelling of z
    np.testing.assert_allclose(results[0], results[1], atol=1e-12)
    assert results[0][1] == pytest.approx(np.tan(az - 2 * np.pi), abs=5e-5)


@pytest.mark.parametrize("name", ["pgm", "enkf", "sir"])
def test_particles_that_hit_a_body_are_removed_and_counted(name):
    # a 'rock' of radius 0.5 at x = 1 swallows the particles that drift into it
    dyn = LinearDynamics(body_radius=0.5, body_x=1.0)
    cloud = ParticleCloud(np.column_stack([np.random.default_rng(0).uniform(-1, 0, (3000, 1)),
                                           np.zeros((3000, 2)), np.ones((3000, 1)), np.zeros((3000, 2))]), 0.0)
    filt = FILTERS[name]()
    filt.initialize(cloud, dyn, LinearSensor(), np.random.default_rng(0))
    filt.predict(1.0)  # x in [0, 1]: those with x > 0.5 are inside the rock
    lost = filt.diagnostics["particles_lost"]
    assert lost > 0
    b = filt.belief
    assert np.all(b.samples.states[:, 0] <= 0.5 + 1e-12)
    assert_finite_belief(b)


def test_update_at_another_time_than_the_belief_is_a_clear_error():
    sensor = LinearSensor()
    filt = PGMFilter(n_particles=500)
    filt.initialize(gaussian_cloud(np.zeros(6), 1.0), LinearDynamics(), sensor, np.random.default_rng(0))
    with pytest.raises(FilterError, match="predict"):
        filt.update(Measurement(1.0, np.zeros(2), np.eye(2), sensor.names))


def test_a_measurement_component_the_sensor_does_not_measure_is_a_clear_error():
    sensor = LinearSensor()
    filt = UKFFilter()
    filt.initialize(gaussian_cloud(np.zeros(6), 1.0), LinearDynamics(), sensor, np.random.default_rng(0))
    with pytest.raises(MeasurementError, match="range"):
        filt.update(Measurement(0.0, np.zeros(1), np.eye(1), ("range",)))


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_a_measurement_with_fewer_components_updates_on_those_only(name):
    sensor = LinearSensor(sigma=0.1)
    filt = FILTERS[name]()
    filt.initialize(gaussian_cloud(np.zeros(6), 1.0), LinearDynamics(), sensor, np.random.default_rng(0))
    filt.update(Measurement(0.0, np.array([0.5]), 0.01 * np.eye(1), ("p1",)))  # only the y coordinate
    m = filt.belief.mixture.mean
    assert m[1] == pytest.approx(0.5 * 1.0 / 1.01, abs=0.1)
    assert abs(m[0]) < 0.1


class _NaNForOne(LinearDynamics):
    """Free motion whose particle 1 comes back NaN, hit (a body stopped it) or not."""

    def __init__(self, dead: bool):
        super().__init__()
        self.dead = dead

    def propagate(self, states, t0, times):
        prop = super().propagate(states, t0, times)
        prop.states[:, 1] = np.nan
        if self.dead:
            prop.alive[1] = False
        return prop


def test_a_nan_state_of_a_live_particle_is_refused_by_name():
    from cistrack.errors import FilterError
    from cistrack.plugins.filters.ensemble_propagation import propagate_ensemble

    with pytest.raises(FilterError, match="filter 'pgm': dynamics returned NaN"):
        propagate_ensemble(_NaNForOne(dead=False), np.ones((4, 6)), 0.0, 1.0, "pgm")


def test_a_nan_state_of_a_dead_particle_is_let_through():
    from cistrack.plugins.filters.ensemble_propagation import propagate_ensemble

    final, alive, _ = propagate_ensemble(_NaNForOne(dead=True), np.ones((4, 6)), 0.0, 1.0, "pgm")
    assert not alive[1] and np.all(np.isfinite(final[alive]))
