"""One way through a run: the truth is propagated once (dense output), every
component is constructed once, custody is a metric stage, one row builder, a typed summary."""
from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from cistrack.evaluation.custody import CustodyMetric, CustodyRule, Verdict
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugin.registry import Registry, load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.evaluation.run_summary import RunSummary
from cistrack.scenario.loading import load_scenario
from cistrack.runs.truth import Truth


def _small(**over):
    base = {"duration_days": 1.4, "filter": {"n_particles": 200, "n_components": 2},
            "iod": {"n_particles": 200}, "run": {"predict_every_hours": 3.0}}
    base.update(over)
    return base


class _CountingRegistry(Registry):
    """The real registry (every real plugin) that counts the components it constructs."""

    def __init__(self, real: Registry) -> None:
        self.__dict__.update(real.__dict__)
        self.created: Counter = Counter()

    def create(self, kind, name, **params):
        self.created[(kind, name)] += 1
        return super().create(kind, name, **params)


def test_loading_and_running_a_scenario_constructs_each_component_once():
    reg = _CountingRegistry(load_registry())
    scen = load_scenario("quick", reg, overrides=_small(filter={"n_particles": 200, "n_components": 2,
                                                                "clusterer": {"name": "kmeans"}}))
    run_scenario(scen, seed=1, registry=reg)
    built = {k: v for k, v in reg.created.items() if k[0] != "orbit"}
    assert set(built.values()) == {1}  # the scenario's components and the parts they are composed of
    assert {("dynamics", "cr3bp"), ("sensor", "ground-telescope"), ("schedule", "paper-example-1"),
            ("iod", "noisy-range"), ("filter", "pgm"), ("clustering", "kmeans")} <= set(built)


def test_a_second_run_of_the_same_scenario_gets_fresh_components():
    scen = load_scenario("quick", overrides=_small())
    first = run_scenario(scen, seed=1).context.filter
    second = run_scenario(scen, seed=1).context.filter
    assert first is not second


class _CountingCR3BP(CR3BP):
    """The real CR3BP, counting its propagations (ensemble and dense) and their spans."""

    calls: list = []

    def propagate(self, states, t0, times, **kw):
        type(self).calls.append(("propagate", np.atleast_1d(np.asarray(times, dtype=float)).copy()))
        return super().propagate(states, t0, times, **kw)

    def dense_trajectory(self, state, t0, t1, **kw):
        type(self).calls.append(("dense", (t0, t1)))
        return super().dense_trajectory(state, t0, t1, **kw)


def test_the_truth_is_propagated_once_per_run_over_the_whole_scenario():
    reg = load_registry()
    reg.add("dynamics", "counting-cr3bp", _CountingCR3BP)
    _CountingCR3BP.calls = []
    scen = load_scenario("quick", reg, overrides=_small(truth={"orbit": "nrho-9-2", "dynamics": "counting-cr3bp"}))
    res = run_scenario(scen, seed=2, registry=reg)
    assert _CountingCR3BP.calls == [("dense", (0.0, scen.duration))]
    assert res.context.truth.propagations == 1
    step_times = [r["t_tu"] for r in res.rows]
    assert set(step_times) <= set(res.context.truth.known_times.tolist())


def test_truth_states_match_a_direct_propagation_to_the_same_times():
    dyn = CR3BP()
    x0 = np.array([1.0214, 0.0, -0.1825, 0.0, -0.1033, 0.0])
    times = np.array([0.1, 0.35, 0.6])
    truth = Truth(dyn, x0, t_end=0.6)
    got = truth.states_at(times[::-1])[::-1]
    np.testing.assert_allclose(got, dyn.propagate(x0[None], 0.0, times).states[:, 0, :], rtol=0, atol=1e-10)
    np.testing.assert_array_equal(got[-1], dyn.propagate(x0[None], 0.0, 0.6).final[0])  # span end: exact
    truth.states_at(times)
    assert truth.propagations == 1


def test_a_truth_time_past_the_span_extends_it_with_one_more_propagation():
    dyn = CR3BP()
    x0 = np.array([1.0214, 0.0, -0.1825, 0.0, -0.1033, 0.0])
    truth = Truth(dyn, x0, t_end=0.3)
    truth.states_at([0.1, 0.2])
    truth.states_at([0.5])
    truth.states_at([0.05, 0.45])
    assert truth.propagations == 2


def test_a_truth_model_without_dense_output_is_propagated_once_per_wave():
    class PlainCR3BP(CR3BP):
        dense_trajectory = None  # as a third-party Dynamics that only has propagate
    truth = Truth(PlainCR3BP(), np.array([1.0214, 0.0, -0.1825, 0.0, -0.1033, 0.0]))
    truth.states_at([0.1, 0.2])
    truth.states_at([0.2, 0.3])
    assert truth.propagations == 2
    np.testing.assert_array_equal(truth.at(0.3), CR3BP().propagate(truth.x0[None], 0.0, 0.3).final[0])


class _Step:
    def __init__(self, index, loglik, hdr):
        self.index, self.t, self.kind, self.truth = index, 0.1 * index, "update", np.zeros(6)
        self.metrics = {"truth_loglik": loglik, "hdr_level": hdr}


@pytest.mark.parametrize("seq,lost_at", [([(5.0, 0.5), (-200.0, 0.5), (5.0, 0.5)], 2),
                                         ([(5.0, 0.999), (5.0, 0.5), (5.0, 0.999), (5.0, 0.999)], 4),
                                         ([(5.0, 0.999), (5.0, 0.5), (5.0, 0.999)], None)])
def test_custody_is_lost_on_low_likelihood_or_consecutive_hdr_excursions(seq, lost_at):
    obs = CustodyMetric(CustodyRule(loglik_threshold=-100.0, hdr_threshold=0.997, hdr_consecutive=2))
    marks = []
    for i, (ll, hdr) in enumerate(seq, start=1):
        marks.append(obs.compute(None, _Step(i, ll, hdr), "updated")["custody"])
    assert obs.verdict.step == lost_at
    if lost_at is None:
        assert obs.verdict.kept and marks == [1.0] * len(seq)
    else:
        assert obs.verdict.kind == "lost" and obs.verdict.reason
        assert marks == [1.0] * (lost_at - 1) + [0.0] * (len(seq) - lost_at + 1)


@pytest.mark.parametrize("loglik,shown", [(-116.04, "-116.0"), (-8.914951e38, "-8.91e+38")])
def test_a_lost_custody_reason_shows_the_likelihood_in_a_few_digits(loglik, shown):
    obs = CustodyMetric(CustodyRule(loglik_threshold=-100.0))
    obs.compute(None, _Step(1, loglik, 0.5), "updated")
    assert obs.verdict.reason == f"truth log-likelihood {shown} < -100"


def test_the_summary_round_trips_through_its_dict_and_reads_old_manifests():
    s = RunSummary("r", 3, verdict=Verdict("lost", "why", 7, 2.5), n_steps=9, final={"nees": 1.0})
    assert RunSummary.from_dict(s.to_dict()) == s
    old = {k: v for k, v in s.to_dict().items() if k != "verdict"}
    back = RunSummary.from_dict(old)
    assert (back.custody_kept, back.custody_lost_step, back.custody_lost_t_days) == (False, 7, 2.5)


def test_the_rows_returned_are_the_rows_written(tmp_path):
    from cistrack.results.store import read_steps

    scen = load_scenario("quick", overrides=_small())
    res = run_scenario(scen, seed=4, output_dir=tmp_path / "r")
    table = read_steps(tmp_path / "r").to_pylist()
    def strip(rows):  # timings differ between writes; NaN != NaN, so compare NaN as a marker;
        # the table has every column in every row (None where a step had no such value)
        return [{k: ("nan" if isinstance(v, float) and np.isnan(v) else v) for k, v in r.items()
                 if not k.startswith("time_") and v is not None} for r in rows]

    assert strip(table) == strip(res.rows)
    assert res.summary.n_steps == len(res.rows)


def test_a_truth_that_starts_inside_the_moon_is_refused_as_such():
    from cistrack.errors import ConfigError

    dyn = CR3BP()
    inside = np.array([1.0 - dyn.mu + 1e-4, 0.0, 0.0, 0.0, 0.0, 0.0])  # 38 km from the Moon's centre
    with pytest.raises(ConfigError, match="initial state lies inside Moon"):
        Truth(dyn, inside, t_end=0.5).states_at([0.1])
