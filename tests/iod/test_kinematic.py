"""Kinematic-fitting IOD on the 9:2 NRHO seen from College Station."""
from __future__ import annotations

import pickle

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.errors import IODError, ParameterError
from cistrack.model.measurement import MeasurementSet
from cistrack.plugins.iod.kinematic import KinematicFitIOD, kinematic_states, prepare_fit
from cistrack.plugins.iod.kinematic_presets import NoisyRangeIOD, UniformRangeIOD, UniformRangeVelocityBoundIOD
from cistrack.plugins.iod.polyfit import truncation_bounds
from cistrack.units import LU_KM, VU_KMS

VARIANTS = ["noisy-range", "uniform-range", "uniform-range-velocity-bound"]
CHI2_99 = chi2.ppf(0.99, 6)


def _mahalanobis2(cloud, x):
    d = x - cloud.mean
    return float(d @ np.linalg.solve(cloud.covariance, d))


def _coverage(registry, scenario, name, trials, seed0, n_particles):
    iod = registry.create("iod", name, n_particles=n_particles)
    inside = 0
    for seed in range(seed0, seed0 + trials):
        rng = np.random.default_rng(seed)
        cloud = iod.estimate(scenario.simulate(rng), scenario.sensor, rng)
        inside += _mahalanobis2(cloud, scenario.truth_states(cloud.epoch)) <= CHI2_99
    return inside


@pytest.mark.parametrize("name", VARIANTS + ["kinematic-fit"])
def test_each_variant_is_registered_as_an_iod_plugin(registry, name):
    assert isinstance(registry.create("iod", name), KinematicFitIOD)


def test_cloud_has_the_requested_particles_at_the_last_fitted_time(scenario, rng):
    ms = scenario.simulate(rng)
    cloud = UniformRangeIOD(n_particles=500).estimate(ms, scenario.sensor, rng)
    assert cloud.states.shape == (500, 6)
    assert cloud.epoch == ms.times[cloud.meta["fit_indices"][-1]]
    assert cloud.meta["fit_indices"] == list(range(8))  # 12 in the first pass: 6 clipped to 8


def test_meta_records_draws_survivors_and_pruning_reasons(scenario, rng):
    cloud = UniformRangeVelocityBoundIOD(n_particles=500).estimate(scenario.simulate(rng),
                                                                   scenario.sensor, rng)
    meta = cloud.meta
    assert meta["survivors"] >= 500
    assert meta["draws"] == meta["survivors"] + sum(meta["pruned"].values())
    assert meta["pruned"]["speed_above_max"] > 0
    assert meta["speed_frame"] == "topocentric"


@pytest.mark.parametrize("name", VARIANTS)
def test_truth_lies_in_the_99_percent_region_fast(registry, scenario, name):
    assert _coverage(registry, scenario, name, trials=10, seed0=1000, n_particles=1000) >= 9


@pytest.mark.slow
@pytest.mark.parametrize("name", VARIANTS)
def test_truth_lies_in_the_99_percent_region_in_95_of_100_trials(registry, scenario, name):
    assert _coverage(registry, scenario, name, trials=100, seed0=0, n_particles=2000) >= 95


def test_range_models_order_cloud_sizes_as_in_figure_19(scenario):
    ms = scenario.simulate(np.random.default_rng(7))
    clouds = {cls: cls(n_particles=3000).estimate(ms, scenario.sensor, np.random.default_rng(8))
              for cls in (NoisyRangeIOD, UniformRangeIOD, UniformRangeVelocityBoundIOD)}

    def pos_sigma(c):
        return np.sqrt(np.trace(clouds[c].covariance[:3, :3])) * LU_KM

    def vel_sigma(c):
        return np.sqrt(np.trace(clouds[c].covariance[3:, 3:])) * VU_KMS

    # noisy range: 5% of ~400,000 km; uniform: the whole cislunar shell
    assert pos_sigma(NoisyRangeIOD) < 0.3 * pos_sigma(UniformRangeIOD)
    assert vel_sigma(NoisyRangeIOD) < 0.3 * vel_sigma(UniformRangeIOD)
    # the speed bound removes the fast tail: velocity spread shrinks by a large factor
    assert vel_sigma(UniformRangeVelocityBoundIOD) < 0.5 * vel_sigma(UniformRangeIOD)


def test_the_same_bound_in_the_synodic_frame_prunes_less(scenario, rng):
    # The Earth-fixed frame adds ~29 km/s of apparent motion at lunar distance; the synodic one
    # (1 rad/TU) adds ~1 km/s, so 42 km/s is a looser bound there.
    ms = scenario.simulate(rng)
    topo = UniformRangeVelocityBoundIOD(n_particles=1000).estimate(ms, scenario.sensor, rng)
    syn = UniformRangeVelocityBoundIOD(n_particles=1000, speed_frame="synodic").estimate(
        ms, scenario.sensor, rng)
    assert syn.meta["survival_fraction"] > topo.meta["survival_fraction"]
    assert np.all(np.linalg.norm(syn.states[:, 3:], axis=1) * VU_KMS <= 42.0)


def test_noise_free_exact_range_fit_is_within_the_truncation_bound(scenario):
    """Noise-free angles and exact ranges: the only error is polynomial truncation.

    Bound (polyfit docstring): |error_i| <= b_j * M_i with M_i = max |x_i^(p+1)| over the window
    (p = 4), b_0/b_1 = sum_k |w_k| |t_k - t_f|^5 / 5! for position/velocity. M_i is estimated from
    a degree-24 Chebyshev fit of 200 truth samples over the window (exact to ~1e-12 for this
    analytic trajectory).
    """
    sensor = scenario.sensor
    times = scenario.times
    truth = scenario.truth_states(times)
    clean = MeasurementSet(times, sensor.measure(truth, times), sensor.sigmas(truth, times), sensor.names)
    fit = prepare_fit(clean, sensor, order=4, pass_gap_hours=3.0, fit_fraction=0.5, min_fit=8,
                      max_fit=12, need_range=True)
    states, _ = kinematic_states(fit, sensor, fit.angles[None], fit.ranges[None])
    err = np.abs(states[0] - scenario.truth_states(fit.epoch))

    dense_t = np.linspace(fit.times[0], fit.times[-1], 200)
    fifth = np.stack([np.polynomial.Chebyshev.fit(dense_t, scenario.truth_states(dense_t)[:, i], 24)
                      .deriv(5)(dense_t) for i in range(3)], axis=1)
    m = np.max(np.abs(fifth), axis=0)
    b0, b1 = truncation_bounds(fit.times, 4, fit.epoch)
    roundoff = 1e-12
    assert np.all(err[:3] <= b0 * m + roundoff)
    assert np.all(err[3:] <= b1 * m + roundoff)
    # and the fit is excellent in absolute terms: well under a km and a cm/s
    assert np.max(err[:3]) * LU_KM < 1.0
    assert np.max(err[3:]) * VU_KMS < 1e-2


def test_noisy_range_without_a_range_component_fails_before_sampling(angles_only_scenario, rng):
    ms = angles_only_scenario.simulate(rng)
    with pytest.raises(IODError, match="needs a measured 'range'"):
        NoisyRangeIOD().estimate(ms, angles_only_scenario.sensor, rng)


def test_uniform_models_ignore_a_measured_range(scenario, angles_only_scenario):
    ms = scenario.simulate(np.random.default_rng(3))
    a = UniformRangeIOD(n_particles=300).estimate(ms, scenario.sensor, np.random.default_rng(4))
    b = UniformRangeIOD(n_particles=300).estimate(ms.without("range"), scenario.sensor,
                                                  np.random.default_rng(4))
    np.testing.assert_array_equal(a.states, b.states)


def test_too_few_survivors_is_an_error_that_says_how_many_and_why(scenario, rng):
    ms = scenario.simulate(rng)
    iod = UniformRangeVelocityBoundIOD(n_particles=1000, max_speed_kms=3.0, oversampling=2.0,
                                       max_oversampling=4.0)
    with pytest.raises(IODError, match=r"only \d+ of 4000 drawn samples survived.*speed above max"):
        iod.estimate(ms, scenario.sensor, rng)


def test_a_first_pass_too_short_for_the_fit_fails_before_sampling(scenario, rng):
    ms = scenario.simulate(rng).subset(np.r_[0:4, 12:17])
    with pytest.raises(IODError, match="first pass has 4 measurement"):
        UniformRangeIOD().estimate(ms, scenario.sensor, rng)


def test_the_same_seed_gives_the_same_cloud(scenario):
    ms = scenario.simulate(np.random.default_rng(5))
    a = NoisyRangeIOD(n_particles=200).estimate(ms, scenario.sensor, np.random.default_rng(6))
    b = NoisyRangeIOD(n_particles=200).estimate(ms, scenario.sensor, np.random.default_rng(6))
    np.testing.assert_array_equal(a.states, b.states)


def test_components_are_picklable_and_report_their_parameters():
    iod = UniformRangeVelocityBoundIOD(n_particles=123, speed_frame="synodic")
    again = pickle.loads(pickle.dumps(iod))
    assert again.get_params() == iod.get_params()
    assert "alpha" not in iod.get_params() and iod.get_params()["speed_frame"] == "synodic"


@pytest.mark.parametrize("params, match", [
    ({"range_prior": 3.0}, "range_prior"),
    ({"order": 0}, "order"),
    ({"min_fit": 4}, "min_fit"),
    ({"range_min_km": 600_000.0}, "range_max_km"),
    ({"speed_frame": "inertial"}, "speed_frame"),
    ({"oversampling": 10.0, "max_oversampling": 5.0}, "max_oversampling"),
])
def test_bad_parameters_are_refused_by_name(params, match):
    with pytest.raises(ParameterError, match=match):
        KinematicFitIOD(**params)
