"""A run's maneuver watch (cistrack.runs.maneuver_watch): the [maneuvers] table, the detection of
the burn of example-1-burn, the response that lets the filter regain custody, the burn's estimate
in summary.maneuvers, and nothing reported for a run without a burn."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.runs.maneuver_watch import episodes
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.interfaces.maneuvers import Detection

SEED = 1


def _scenario(name: str, **tables):
    return load_scenario(name).with_overrides(tables) if tables else load_scenario(name)


@pytest.fixture(scope="module")
def burn_run():
    return run_scenario(_scenario("example-1-burn"), seed=SEED)


@pytest.fixture(scope="module")
def baseline_run():
    return run_scenario(_scenario("example-1-burn", maneuvers={"response": "none"},
                                  custody={"regain_updates": 0}), seed=SEED)


def test_a_pgm_scenario_watches_with_the_mixture_likelihood_detector():
    assert _scenario("example-1").maneuvers.detector.name == "mixture-likelihood"


def test_a_ukf_scenario_watches_with_the_nis_window_detector():
    assert _scenario("example-1", filter={"name": "ukf"}).maneuvers.detector.name == "nis-window"


def test_detector_none_switches_the_watch_off():
    result = run_scenario(_scenario("quick", maneuvers={"detector": "none"}), seed=SEED)
    assert result.context.maneuvers is None
    assert "maneuver_statistic" not in result.rows[-1]


def test_a_detector_table_without_a_name_sets_the_automatic_detectors_parameters():
    spec = _scenario("example-1", maneuvers={"detector": {"window": 4}}).maneuvers.detector
    assert (spec.name, spec.params["window"]) == ("mixture-likelihood", 4)


@pytest.mark.parametrize("table, words", [
    ({"detector": "no-such"}, "[maneuvers] detector"),
    ({"detector": "none", "response": "inflate"}, "needs a detector"),
    ({"response": "no-such"}, "[maneuvers] response"),
    ({"estimate": "yes"}, "estimate"),
    ({"bogus": 1}, "unknown key 'bogus'"),
])
def test_a_bad_maneuvers_table_is_refused_by_name(table, words):
    with pytest.raises(ConfigError, match=None) as err:
        _scenario("example-1", maneuvers=table)
    assert words in str(err.value)


def test_every_update_row_has_the_detectors_statistic(burn_run):
    ups = [r for r in burn_run.rows if r["kind"] == "update"]
    assert all(np.isfinite(r["maneuver_statistic"]) and r["maneuver_detected"] in (0.0, 1.0) for r in ups)


def test_the_burn_is_detected_after_it_and_reported_once(burn_run):
    (m,) = burn_run.summary.maneuvers
    (truth,) = burn_run.summary.truth_maneuvers
    assert truth["t_days"] < m["t_days"] < truth["t_days"] + 2.0


def test_the_estimated_delta_v_is_within_three_sigma_of_the_truth(burn_run):
    (m,) = burn_run.summary.maneuvers
    (truth,) = burn_run.summary.truth_maneuvers
    assert m["confirmed"]
    assert abs(m["delta_v_ms"] - truth["delta_v_ms"]) <= 3 * m["delta_v_sigma_ms"]
    assert abs(m["t_burn_days"] - truth["t_days"]) <= 3 * m["t_burn_sigma_days"]


def test_the_run_summary_names_the_truth_burn_and_the_estimate(burn_run):
    from cistrack.evaluation.run_summary import maneuver_lines

    (m,) = burn_run.summary.maneuvers
    truth_line, found = maneuver_lines(burn_run.summary)
    assert truth_line == "  truth burn: 1 m/s at 3.620 d"
    assert found.startswith(f"  maneuver 1: detected at {m['t_days']:.3f} d; burn ")
    assert f"{m['delta_v_ms']:.3g} +- " in found and f"at {m['t_burn_days']:.3f} +- " in found


def test_a_ballistic_run_without_detections_has_no_maneuver_lines():
    from cistrack.evaluation.run_summary import RunSummary, maneuver_lines

    assert maneuver_lines(RunSummary(run_id="r", seed=1)) == []


def test_with_the_response_custody_is_kept_through_the_burn(burn_run):
    """Kept throughout (the burn detected at the first update after it, the filter widened before
    it takes that update) or lost and regained: either way the verdict keeps custody."""
    v = burn_run.summary.verdict
    assert v.kept and v.kind == "tracking"


def test_without_maneuver_handling_the_burn_loses_the_track(baseline_run):
    assert not baseline_run.summary.verdict.kept
    assert baseline_run.summary.maneuvers  # still detected and reported


def test_the_manifest_summary_round_trips_the_maneuvers(burn_run):
    from cistrack.evaluation.run_summary import RunSummary

    again = RunSummary.from_dict(burn_run.summary.to_dict())
    assert again.maneuvers == burn_run.summary.to_dict()["maneuvers"]
    assert again.truth_maneuvers == burn_run.summary.truth_maneuvers


def test_a_run_without_a_burn_reports_none():
    result = run_scenario(_scenario("example-1"), seed=SEED)
    assert result.summary.maneuvers == [] and result.summary.truth_maneuvers == []


def test_detections_close_together_are_one_episode():
    def d(t):
        return Detection(t=t, statistic=9.0, threshold=4.0)

    groups = episodes([d(1.0), d(1.05), d(1.1), d(3.0)])  # TU: 1.5 days is 0.345 TU
    assert [len(g) for g in groups] == [3, 1]


def test_adding_the_maneuver_stream_leaves_the_other_streams_as_they_were():
    from cistrack.runs.pipeline import _streams

    old = np.random.SeedSequence(7).spawn(4)
    new = _streams(7)
    for name, child in zip(("measurements", "schedule", "iod", "filter"), old):
        assert new[name].random() == np.random.default_rng(child).random()


def test_a_detector_whose_warmup_covers_every_update_says_it_can_detect_nothing():
    from cistrack.scenario.settings import apply_settings

    s = apply_settings(load_scenario("example-1-burn"), ["duration_days=1.4", "filter.n_particles=200",
                                                          "filter.n_components=2", "iod.n_particles=200",
                                                          "maneuvers.detector.warmup=400"])
    lines: list[str] = []
    run_scenario(s, seed=SEED, log=lines.append)
    said = [m for m in lines if "warmup = 400 covers all" in m]
    assert len(said) == 1 and "can detect nothing" in said[0] and "mixture-likelihood" in said[0]


def test_a_detection_not_estimated_is_recorded_and_said_as_not_estimated_not_as_rejected():
    from types import SimpleNamespace

    from cistrack.evaluation.run_summary import maneuver_lines
    from cistrack.runs.maneuver_watch import _record

    d = Detection(t=3.0, statistic=5.0, threshold=4.0, detector="nis-window", t_burn_bounds=(2.9, 3.0))
    rec = _record([d], None, estimated=False)
    assert rec["confirmed"] is None and _record([d], None)["confirmed"] is False
    [line] = maneuver_lines(SimpleNamespace(truth_maneuvers=[], maneuvers=[rec]))
    assert line.endswith("not estimated ([maneuvers] estimate = false)")


def test_an_estimated_burn_is_recorded_with_the_covariance_of_its_delta_v_vector(burn_run):
    [m] = [m for m in burn_run.summary.maneuvers if m.get("confirmed")][:1]
    cov = np.asarray(m["delta_v_covariance_ms2"])
    assert cov.shape == (3, 3) and np.allclose(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)
    u = np.asarray(m["delta_v_vector_ms"]) / m["delta_v_ms"]
    across = (np.eye(3) - np.outer(u, u)) @ cov @ (np.eye(3) - np.outer(u, u))
    size_variance = u @ cov @ u + np.sum(across * across) / (2.0 * m["delta_v_ms"] ** 2)  # along dv, and |dv|'s curvature
    assert np.sqrt(size_variance) == pytest.approx(m["delta_v_sigma_ms"], rel=1e-9)


def test_the_default_watch_of_a_run_too_short_for_it_says_nothing():
    """cistrack fit's own filter run over a first tracklet had printed advice to lower a warmup
    nobody had set."""
    from cistrack.scenario.settings import apply_settings

    s = apply_settings(load_scenario("quick"), ["duration_days=1.3", "filter.n_particles=200", "iod.n_particles=200"])
    assert not s.maneuvers.asked and s.maneuvers.detector is not None
    lines: list[str] = []
    run_scenario(s, seed=SEED, log=lines.append)
    assert not [m for m in lines if "can detect nothing" in m]
