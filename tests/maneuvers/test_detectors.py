"""The built-in maneuver detectors, nis-window and mixture-likelihood: what they compute, their
false-alarm rate against the declared level on consistent data, and their delay on steps."""
from __future__ import annotations

import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import binom, chi2

from cistrack.errors import FilterError, MeasurementError, ParameterError
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.model.innovation import innovation
from cistrack.model.measurement import Measurement, StackedMeasurement
from cistrack.plugin.registry import Registry
from cistrack.plugins.maneuvers.detectors import MixtureLikelihoodDetector, NisWindowDetector
from cistrack.plugins.maneuvers.predictive_mixture import predictive_mixture, tail_probability
from cistrack.testing.checks_maneuver_detectors import PlanePositionSensor, linear_gaussian_updates

DETECTORS = [NisWindowDetector, MixtureLikelihoodDetector]


def _run(det, seq):
    det.reset()
    return [det.observe(float(t), p, g, seq.sensor) for t, p, g in zip(seq.times, seq.priors, seq.groups)]


def test_both_are_registered_as_maneuver_detectors():
    """By the module's hook (the installed entry point ``maneuver-detectors`` names the module)."""
    from cistrack.plugins.maneuvers import detectors

    reg = Registry()
    detectors.cistrack_register(reg)
    assert reg.get("maneuver-detector", "nis-window").factory is NisWindowDetector
    assert reg.get("maneuver-detector", "mixture-likelihood").factory is MixtureLikelihoodDetector


@pytest.mark.parametrize("cls", DETECTORS)
@pytest.mark.parametrize(("params", "named"), [
    ({"window": 0}, "window"), ({"false_alarm": 0.0}, "false_alarm"), ({"false_alarm": 0.7}, "false_alarm"),
    ({"warmup": -1}, "warmup"), ({"min_surprising": 6}, "min_surprising"),
    ({"update_level": 1e-6}, "update_level"), ({"window": 2.5}, "window"),
    ({"gap_hours": 0.0}, "gap_hours"), ({"gap_hours": -1.0}, "gap_hours"), ({"gap_hours": "6"}, "gap_hours")])
def test_bad_parameters_name_the_parameter_and_what_is_allowed(cls, params, named):
    with pytest.raises(ParameterError, match=f"'{named}'.*must"):
        cls(**params)


def test_mixture_parameters_are_checked():
    with pytest.raises(ParameterError, match="'n_draws'"):
        MixtureLikelihoodDetector(n_draws=-1)
    with pytest.raises(ParameterError, match="'seed'"):
        MixtureLikelihoodDetector(seed=-3)


def test_nis_window_statistic_is_the_surprise_of_the_nis():
    seq = linear_gaussian_updates(3, seed=1)
    det = NisWindowDetector(warmup=0, window=1, min_surprising=1)
    stat, _ = det.observe(seq.times[0], seq.priors[0], seq.groups[0], seq.sensor)
    inn = innovation(seq.priors[0], seq.groups[0], seq.sensor)
    assert stat == pytest.approx(-chi2.logsf(inn.nis, 2) / math.log(10), rel=1e-9)


def test_nis_window_sums_the_window():
    seq = linear_gaussian_updates(3, seed=2)
    det = NisWindowDetector(warmup=0, window=3, min_surprising=1)
    nis = [innovation(p, g, seq.sensor).nis for p, g in zip(seq.priors, seq.groups)]
    dofs = [2 * len(g) for g in seq.groups]
    stats = [s for s, _ in _run(det, seq)]
    single = -chi2.logsf(nis[-1], dofs[-1]) / math.log(10)
    window = -chi2.logsf(sum(nis), sum(dofs)) / math.log(10)
    assert stats[-1] == pytest.approx(max(single, window), rel=1e-9)


def test_one_gaussian_mixture_likelihood_equals_the_nis_test():
    """For one Gaussian and a linear sensor the predictive density's tail is the chi-square tail
    of the Mahalanobis distance: both detectors judge each update alike (their windows differ:
    a sum of NIS against one chi-square, Fisher's method on the p-values)."""
    seq = linear_gaussian_updates(12, seed=4)
    a = [s for s, _ in _run(NisWindowDetector(warmup=0, window=1, min_surprising=1), seq)]
    b = [s for s, _ in _run(MixtureLikelihoodDetector(warmup=0, window=1, min_surprising=1), seq)]
    assert np.allclose(a, b, rtol=1e-6, atol=1e-9)


def _two_component_problem(seed: int, shift_sigmas: float = 0.0):
    """A prior of two well-separated Gaussians in x, the truth drawn from it, z = (x, y) + noise."""
    rng = np.random.default_rng(seed)
    sig = np.array([3e-4, 3e-4, 3e-4, 1e-6, 1e-6, 1e-6])
    means = np.array([[1.0, 0.0, -0.18, 0.0, -0.1, 0.0], [1.0 + 2e-3, 1e-3, -0.18, 0.0, -0.1, 0.0]])
    mix = GaussianMixture(np.array([0.3, 0.7]), means, np.array([np.diag(sig ** 2)] * 2))
    samples, _ = mix.sample(500, rng)
    truth = mix.sample(1, rng)[0][0]
    r = np.eye(2) * 1e-4 ** 2
    z = truth[:2] + 1e-4 * rng.standard_normal(2) + np.array([shift_sigmas * 3.2e-4, 0.0])
    return Belief(0.5, mix, ParticleCloud(samples, 0.5)), [Measurement(0.5, z, r, ("x", "y"))]


def test_tail_probability_matches_a_large_monte_carlo_and_the_bound_lies_above():
    sensor = PlanePositionSensor()
    for seed in range(6):
        prior, group = _two_component_problem(seed, shift_sigmas=seed * 0.6)
        w, m, c = predictive_mixture(prior, group, sensor)
        log_p, parts = tail_probability(w, m, c, 2000, 1, 0.5)
        rng = np.random.default_rng(99)
        lab = rng.choice(2, 200_000, p=w)
        zz = m[lab] + np.einsum("nij,nj->ni", np.linalg.cholesky(c)[lab], rng.standard_normal((200_000, 2)))
        mix = GaussianMixture(w, m, c)
        ref = np.mean(mix.logpdf(zz) <= parts["log_density"])
        assert parts["log_p_bound"] >= math.log(ref) - 0.05
        assert abs(math.exp(log_p) - ref) < 0.03 + 3 * math.sqrt(ref / 2000)


def test_a_far_observation_is_judged_by_the_analytic_bound_below_the_monte_carlo_floor():
    prior, group = _two_component_problem(0, shift_sigmas=30.0)
    w, m, c = predictive_mixture(prior, group, PlanePositionSensor())
    log_p, parts = tail_probability(w, m, c, 2000, 1, 0.5)
    assert parts["log_p_mc"] == pytest.approx(math.log(1 / 2001))
    assert log_p == parts["log_p_bound"] < math.log(1e-20)


def test_the_mixture_falls_back_to_one_gaussian_from_the_samples():
    seq = linear_gaussian_updates(1, seed=5)
    prior = seq.priors[0]
    no_mixture = SimpleNamespace(epoch=prior.epoch, mixture=None, samples=prior.samples)
    det = MixtureLikelihoodDetector(warmup=0)
    a = det.observe(1.0, prior, seq.groups[0], seq.sensor)[0]
    det.reset()
    b = det.observe(1.0, no_mixture, seq.groups[0], seq.sensor)[0]
    assert a == pytest.approx(b, rel=1e-2)  # the samples' covariance is the unbiased one: 400/399


_SUBPROCESS = """
import sys
sys.path.insert(0, {tests!r})
from test_detectors import _two_component_problem
from cistrack.plugins.maneuvers.detectors import MixtureLikelihoodDetector
from cistrack.testing.checks_maneuver_detectors import PlanePositionSensor
det = MixtureLikelihoodDetector(warmup=0)
prior, group = _two_component_problem(3, 1.5)
print(repr(det.observe(0.5, prior, group, PlanePositionSensor())[0]))
"""


def test_mixture_likelihood_gives_the_same_statistic_in_another_process():
    from pathlib import Path

    prior, group = _two_component_problem(3, 1.5)
    here = MixtureLikelihoodDetector(warmup=0).observe(0.5, prior, group, PlanePositionSensor())[0]
    code = _SUBPROCESS.format(tests=str(Path(__file__).parent))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert float(out.stdout.strip()) == here


def test_the_seed_changes_only_the_monte_carlo():
    prior, group = _two_component_problem(3, 1.5)
    a = MixtureLikelihoodDetector(warmup=0, seed=1).observe(0.5, prior, group, PlanePositionSensor())[0]
    b = MixtureLikelihoodDetector(warmup=0, seed=2).observe(0.5, prior, group, PlanePositionSensor())[0]
    assert a != b and abs(a - b) < 0.1


@pytest.mark.parametrize("cls", DETECTORS)
def test_false_alarm_rate_on_consistent_data_is_the_declared_level(cls):
    """At false_alarm = 0.01 with one update needed: the single-update test alone fires at 0.01,
    window and single together at most 0.02 (union bound); 0.999 binomial bounds over 1500
    updates of three fixed seeds."""
    n, fired = 0, 0
    for seed in (21, 22, 23):
        seq = linear_gaussian_updates(500, seed)
        fired += sum(d is not None for _, d in _run(cls(false_alarm=0.01, warmup=0, min_surprising=1), seq))
        n += 500
    assert binom.ppf(0.001, n, 0.01) <= fired <= binom.ppf(0.999, n, 0.02)


def test_mixture_false_alarm_rate_on_a_two_component_prior():
    """The Monte Carlo path (two components): truth drawn from the prior mixture itself."""
    det = MixtureLikelihoodDetector(false_alarm=0.01, warmup=0, min_surprising=1, window=1)
    fired, n = 0, 600
    sensor = PlanePositionSensor()
    for k in range(n):
        prior, group = _two_component_problem(1000 + k)
        det.reset()
        fired += det.observe(0.5, prior, group, sensor)[1] is not None
    assert binom.ppf(0.001, n, 0.01) <= fired <= binom.ppf(0.999, n, 0.01)


@pytest.mark.parametrize("cls", DETECTORS)
def test_default_false_alarms_are_rare_on_consistent_data(cls):
    seq = linear_gaussian_updates(1000, seed=31)
    assert sum(d is not None for _, d in _run(cls(), seq)) <= binom.ppf(0.999, 990, 2e-4)


@pytest.mark.parametrize("cls", DETECTORS)
def test_detection_delay_shrinks_with_the_step_size(cls):
    """Defaults (window 5, two surprising updates in it): a step of 50 or 20 innovation
    sigmas is detected at the second update after it, 8 sigmas within three, 4 within six."""
    delays = {}
    for size, most in ((50.0, 1), (20.0, 1), (8.0, 2), (4.0, 5)):
        seq = linear_gaussian_updates(40, seed=7, step_at=20, step_sigmas=size)
        hits = [i for i, (_, d) in enumerate(_run(cls(), seq)) if d is not None]
        assert hits and hits[0] >= 20, (size, hits)
        delays[size] = hits[0] - 20
        assert delays[size] <= most, delays
    assert delays[50.0] <= delays[20.0] <= delays[8.0] <= delays[4.0]


@pytest.mark.parametrize("cls", DETECTORS)
def test_t_burn_bounds_run_from_the_last_update_before_the_step(cls):
    seq = linear_gaussian_updates(30, seed=8, step_at=20)
    det = next(d for _, d in _run(cls(), seq) if d is not None)
    assert det.t_burn_bounds == (seq.times[19], det.t) and det.t == seq.times[21]
    assert det.delta_v is None and det.detector == cls.registry_name
    assert det.statistic >= det.threshold == pytest.approx(4.0)


@pytest.mark.parametrize("cls", DETECTORS)
def test_one_gross_outlier_fires_only_when_one_surprising_update_suffices(cls):
    seq = _with_gross_update(linear_gaussian_updates(30, seed=9), 20)
    assert not any(d for _, d in _run(cls(), seq))
    hits = [i for i, (_, d) in enumerate(_run(cls(min_surprising=1), seq)) if d is not None]
    assert hits == [20]


@pytest.mark.parametrize("cls", DETECTORS)
def test_after_a_detection_the_test_starts_again(cls):
    """A lasting step fires, then again only once min_surprising new updates are surprising."""
    seq = linear_gaussian_updates(30, seed=10, step_at=20)
    hits = [i for i, (_, d) in enumerate(_run(cls(), seq)) if d is not None]
    assert hits[:3] == [21, 23, 25]


@pytest.mark.parametrize("cls", DETECTORS)
def test_warmup_updates_never_fire(cls):
    seq = linear_gaussian_updates(14, seed=12, step_at=0)
    hits = [i for i, (_, d) in enumerate(_run(cls(warmup=10), seq)) if d is not None]
    assert hits[0] == 11


@pytest.mark.parametrize("cls", DETECTORS)
def test_a_stacked_measurement_is_its_parts(cls):
    seq = linear_gaussian_updates(4, seed=13)
    group = seq.groups[3]
    assert len(group) == 2
    a = cls(warmup=0).observe(seq.times[3], seq.priors[3], group, seq.sensor)
    b = cls(warmup=0).observe(seq.times[3], seq.priors[3], StackedMeasurement(tuple(group)), seq.sensor)
    assert a[0] == b[0]


@pytest.mark.parametrize("cls", DETECTORS)
def test_updates_out_of_time_order_or_without_measurements_are_refused(cls):
    seq = linear_gaussian_updates(2, seed=14)
    det = cls()
    det.observe(seq.times[1], seq.priors[1], seq.groups[1], seq.sensor)
    with pytest.raises(MeasurementError, match="time order"):
        det.observe(seq.times[0], seq.priors[0], seq.groups[0], seq.sensor)
    with pytest.raises(MeasurementError, match="at least one measurement"):
        cls().observe(seq.times[0], seq.priors[0], [], seq.sensor)


def _with_gross_update(seq, k, sigmas=50.0):
    m = seq.groups[k][0]
    seq.groups[k] = [Measurement(m.t, m.z + np.array([sigmas * seq.sigma_x, 0.0]), m.covariance, m.names)]
    return seq


def _with_gap(seq, k, hours):
    """The updates from ``k`` on moved ``hours`` later: a gap between updates k-1 and k."""
    from dataclasses import replace

    from cistrack import units

    shift = float(units.days_to_tu(hours / 24.0))
    for j in range(k, len(seq.times)):
        t = float(seq.times[j] + shift)
        seq.times[j] = t
        b = seq.priors[j]
        seq.priors[j] = Belief(t, b.mixture, replace(b.samples, epoch=t))
        seq.groups[j] = [replace(m, t=t) for m in seq.groups[j]]
    return seq


@pytest.mark.parametrize("cls", DETECTORS)
def test_a_gross_first_update_after_a_gap_fires_alone(cls):
    """A burn in a gap between passes shows first at the pass's first update, where a filter with
    a wide prior may absorb it: that update fires by itself when it is gross."""
    seq = _with_gap(_with_gross_update(linear_gaussian_updates(30, seed=9), 20), 20, hours=12.0)
    hits = [i for i, (_, d) in enumerate(_run(cls(), seq)) if d is not None]
    assert hits == [20]


@pytest.mark.parametrize("cls", DETECTORS)
def test_a_gross_update_after_a_shorter_gap_than_gap_hours_needs_a_second_surprising_one(cls):
    seq = _with_gap(_with_gross_update(linear_gaussian_updates(30, seed=9), 20), 20, hours=12.0)
    assert not any(d for _, d in _run(cls(gap_hours=14.0), seq))  # the gap is 12 h + the 1 h spacing
    assert not any(d for _, d in _run(cls(gap_hours=float("inf")), seq))


@pytest.mark.parametrize("cls", DETECTORS)
def test_a_merely_surprising_first_update_after_a_gap_does_not_fire_alone(cls):
    """Surprising at the 1 % level but not gross (below false_alarm): the gap rule does not apply."""
    seq = _with_gap(_with_gross_update(linear_gaussian_updates(30, seed=9), 20, sigmas=1.5), 20, hours=12.0)
    results = _run(cls(), seq)
    assert 2.0 < results[20][0] < 4.0  # surprise: beyond the 1 % level, short of false_alarm's 4
    assert not any(d for _, d in results)


@pytest.mark.parametrize("cls", DETECTORS)
def test_t_burn_bounds_reach_back_to_a_recent_gross_update_the_filter_absorbed(cls):
    """A burn the filter absorbs at its first update (gross there, consistent after) and that is
    detected later: the bounds start before the gross update, within five windows; an older
    gross update is forgotten."""
    seq = _with_gross_update(linear_gaussian_updates(40, seed=15, step_at=26), 20)
    det = next(d for _, d in _run(cls(), seq) if d is not None)
    assert det.t == seq.times[27] and det.t_burn_bounds == (seq.times[19], det.t)
    seq = _with_gross_update(linear_gaussian_updates(50, seed=15, step_at=36), 8)  # 28 updates back: > 5 windows
    det = next(d for _, d in _run(cls(), seq) if d is not None)
    assert det.t_burn_bounds == (seq.times[35], det.t)


def test_a_prior_without_finite_numbers_is_refused_by_name():
    seq = linear_gaussian_updates(1, seed=16)
    p = seq.priors[0]
    bad = Belief(p.epoch, p.mixture, ParticleCloud(np.full_like(p.samples.states, np.nan), p.epoch))
    with pytest.raises(FilterError, match="nis-window|NisWindowDetector"):
        NisWindowDetector().observe(seq.times[0], bad, seq.groups[0], seq.sensor)
