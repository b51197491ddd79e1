"""The maneuver response ``reanchor`` (re-anchoring by least squares with an impulsive burn) and the
history a response with ``needs_history`` is handed; a response written against the four-argument
``respond`` still runs."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ParameterError
from cistrack.interfaces.maneuvers import ManeuverResponse, ResponseHistory
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.plugin.registry import Registry
from cistrack.plugins.maneuvers.reanchor import burn_candidates
from cistrack.plugins.maneuvers.responses import InflateResponse, ReanchorResponse
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings

SEED = 1
SMALL = ["filter.n_particles=1000", "filter.n_components=3", "iod.n_particles=1000", "duration_days=5.4",
         "run.predict_every_hours=12"]
BURN_DAYS = 3.62


def _burn_scenario(response: str, *items: str, registry=None):
    return apply_settings(load_scenario("example-1-burn", registry=registry),
                          [*SMALL, f'maneuvers.response="{response}"', *items], registry)


@pytest.fixture(scope="module")
def reanchor_run():
    lines: list[str] = []
    result = run_scenario(_burn_scenario("reanchor"), seed=SEED, log=lines.append)
    return result, lines


def _refit(result):
    """The run's first detection, its history and the filter's prior there (a cloud near the truth)."""
    watch, ctx = result.context.maneuvers, result.context
    d = replace(watch.detections[0], extra={})   # a copy: the run's own stays as the run left it
    history = watch.history(ctx, d)
    truth = ctx.truth.states_at([d.t])[0]
    x = truth + 1e-6 * np.random.default_rng(3).standard_normal((400, 6))
    mixture = GaussianMixture(np.ones(1), truth[None].copy(), (1e-12 * np.eye(6))[None])
    return d, history, Belief(float(d.t), mixture, ParticleCloud(x, float(d.t))), ctx.dynamics


def test_reanchor_refits_the_burn_and_the_filter_keeps_custody(reanchor_run):
    result, lines = reanchor_run
    d = result.context.maneuvers.detections[0]
    note = d.extra["reanchor"]
    assert note["fallback"] is None
    assert abs(units.tu_to_days(note["t_burn"]) - BURN_DAYS) < 0.3      # in the gap before the pass it showed in
    assert 0.5 < np.linalg.norm(note["delta_v_ms"]) < 1.5               # the truth's: 1 m/s
    assert any(line.startswith("reanchor: refitted with a burn") for line in lines)
    assert result.summary.verdict.kept


def test_the_refit_cloud_holds_the_truth_at_the_detection(reanchor_run):
    result, _ = reanchor_run
    d, history, prior, dynamics = _refit(result)
    cloud = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(5), history=history)
    x = np.asarray(cloud.states)
    truth = result.context.truth.states_at([d.t])[0]
    e = truth - x.mean(axis=0)
    assert float(e @ np.linalg.solve(np.cov(x, rowvar=False), e)) < 30.0   # chi-square 6 dof: far inside
    assert x.shape == (400, 6) and cloud.epoch == d.t


def test_the_history_stops_before_the_detection_and_starts_from_a_settled_posterior(reanchor_run):
    result, _ = reanchor_run
    d, history, _, _ = _refit(result)
    assert np.all(np.asarray(history.measurements.times) < d.t)
    assert history.posterior is not None and history.posterior.t < d.t_burn_bounds[0]


def test_the_same_generator_seed_gives_the_same_cloud(reanchor_run):
    d, history, prior, dynamics = _refit(reanchor_run[0])
    a = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(11), history=history)
    b = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(11), history=history)
    c = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(12), history=history)
    assert np.array_equal(a.states, b.states) and not np.array_equal(a.states, c.states)


def test_without_a_history_it_does_what_inflate_does_and_says_so(reanchor_run):
    d, _, prior, dynamics = _refit(reanchor_run[0])
    got = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(4))
    want = InflateResponse().respond(d, prior, dynamics, np.random.default_rng(4))
    assert np.array_equal(got.states, want.states)
    assert "no history" in d.extra["reanchor"]["fallback"]


def test_too_few_measurements_fall_back_to_inflate_in_the_log(reanchor_run):
    d, history, prior, dynamics = _refit(reanchor_run[0])
    lines: list[str] = []
    times = np.asarray(history.measurements.times)
    short = ResponseHistory(history.measurements.subset(times <= history.posterior.t + 1e-9), history.sensor,
                            history.posterior, lines.append)
    got = ReanchorResponse().respond(d, prior, dynamics, np.random.default_rng(4), history=short)
    want = InflateResponse().respond(d, prior, dynamics, np.random.default_rng(4))
    assert np.array_equal(got.states, want.states)
    assert len(lines) == 1 and "inflating instead" in lines[0] and "measurements" in lines[0]


def test_burn_candidates_share_the_arcs_long_gaps_by_length():
    t = np.array([0.0, 0.01, 0.02, 0.5, 0.51])              # TU: 0.01 TU is 1 h, a gap between tracklets
    c = burn_candidates(t, -0.3, 0.52)
    long_gap, before = (c > 0.02) & (c < 0.5), (c > -0.3) & (c < 0.0)
    assert np.sum(long_gap) > np.sum(before) >= 1 and np.all(long_gap | before | (c < 0.52))
    assert np.all(np.diff(c) > 0)


def test_a_bad_delta_v_sigma_is_refused_by_name():
    with pytest.raises(ParameterError, match="delta_v_sigma_ms"):
        ReanchorResponse(delta_v_sigma_ms=-1.0)


class _FourArguments(ManeuverResponse):
    """A third-party response written against the four-argument respond()."""

    default_name = "four-arguments"
    calls: list = []

    def respond(self, detection, prior, dynamics, rng):
        type(self).calls.append(float(detection.t))
        return None


def test_a_response_with_the_four_argument_respond_still_runs():
    reg = Registry().load_entry_points()
    reg.add("maneuver-response", "four-arguments", _FourArguments)
    _FourArguments.calls = []
    result = run_scenario(_burn_scenario("four-arguments", registry=reg), seed=SEED, registry=reg)
    assert _FourArguments.calls and _FourArguments.calls[0] == result.context.maneuvers.detections[0].t


class _AsksButTakesNoHistory(_FourArguments):
    """Sets needs_history but kept the four-argument respond()."""

    default_name = "asks-but-takes-none"
    needs_history = True


def test_conformance_refuses_a_response_that_asks_for_a_history_it_cannot_take():
    from cistrack.testing.checks_maneuvers import check_response_takes_the_history_it_asks_for

    check_response_takes_the_history_it_asks_for(ReanchorResponse())
    with pytest.raises(AssertionError, match="history"):
        check_response_takes_the_history_it_asks_for(_AsksButTakesNoHistory())


def _anchors(log_evidences):
    from cistrack.plugins.maneuvers.reanchor import Anchor

    return [Anchor(tb=0.1 * k, log_evidence=e, cost=0.0, mean=np.zeros(6), covariance=np.eye(6) * 1e-8,
                   dv=np.zeros(3)) for k, e in enumerate(log_evidences)]


def test_reanchor_says_when_the_measurements_cannot_place_the_burn():
    from cistrack.interfaces.maneuvers import Detection
    from cistrack.plugins.maneuvers.reanchor import draw

    lines: list[str] = []
    draw(Detection(t=3.0, statistic=5.0, threshold=4.0), _anchors([0.0] * 26), 50, np.random.default_rng(0),
         lines.append)
    assert "cannot place the burn yet (largest weight 0.04 of 26 candidate times)" in lines[0]
    lines.clear()
    draw(Detection(t=3.0, statistic=5.0, threshold=4.0), _anchors([0.0] * 25 + [20.0]), 50, np.random.default_rng(0),
         lines.append)
    assert lines[0].startswith("reanchor: refitted with a burn at")
