"""Burns in a scenario: [truth.maneuvers] loads, takes --set, and the truth of a run (never the
filter's model) jumps in velocity by each burn's dv; the built-in scenarios example-1-burn and
example-1-maneuver."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.plugins.maneuvers.local_frames import frame_axes
from cistrack.propagation.impulses import MS_PER_VU, ImpulsiveDynamics
from cistrack.runs.pipeline import prepare_run, run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings, parse_settings

SMALL = ["filter.n_particles=200", "filter.n_components=2", "iod.n_particles=200"]
NRHO_PERIOD_DAYS = 1.5121455320848902 * units.TU_DAYS


def _scenario(name: str, *items: str):
    return apply_settings(load_scenario(name), [*SMALL, *items])


def test_the_built_in_burn_scenarios_load_with_their_plans():
    burn = load_scenario("example-1-burn").truth_maneuvers
    assert (burn.kind, burn.name) == ("maneuver-plan", "impulse")
    assert burn.params == {"t_days": 3.62, "delta_v_ms": 1.0, "direction": "in-track", "frame": "rtn-moon"}
    sk = load_scenario("example-1-maneuver")
    assert sk.truth_maneuvers.name == "station-keeping" and sk.truth_maneuvers.params["n_burns"] == 2
    assert 2 * NRHO_PERIOD_DAYS < sk.duration_days < 3 * NRHO_PERIOD_DAYS  # two revolutions, and days to see the second burn
    assert load_scenario("example-1").truth_maneuvers is None


def test_set_changes_the_plan_and_a_new_name_replaces_its_table():
    assert parse_settings(["truth.maneuvers.delta_v_ms=0.3"]) == {"truth": {"maneuvers": {"delta_v_ms": 0.3}}}
    s = apply_settings(load_scenario("example-1-burn"), ["truth.maneuvers.delta_v_ms=0.3", "truth.maneuvers.t_days=2"])
    assert s.truth_maneuvers.params["delta_v_ms"] == 0.3 and s.truth_maneuvers.params["t_days"] == 2.0
    assert s.truth_orbit == "nrho-9-2"                               # the rest of [truth] is kept
    with pytest.warns(UserWarning, match=r"t_days = 3\.62, .* dropped with it"):  # the burn's keys, said
        s = apply_settings(load_scenario("example-1-burn"), ['truth.maneuvers.name="station-keeping"'])
    assert s.truth_maneuvers.name == "station-keeping" and "t_days" not in s.truth_maneuvers.params
    s = apply_settings(load_scenario("example-1"), ['truth.maneuvers.name="impulse"', "truth.maneuvers.t_days=1.5"])
    assert s.truth_maneuvers.params == {"t_days": 1.5}


def test_a_list_of_burns_is_a_table_array():
    s = apply_settings(load_scenario("example-1"), [
        'truth.maneuvers={name="burns", burns=[{t_days=1.5, delta_v_ms=0.5}, {t_days=2.5, vector_ms=[0, 0.2, 0]}]}'])
    assert s.truth_maneuvers.name == "burns" and len(s.truth_maneuvers.params["burns"]) == 2


@pytest.mark.parametrize("item, words", [
    ("truth.maneuvers.delta_v_ms=-1", ["[truth.maneuvers]", "delta_v_ms", "[0.0, 10000.0]"]),
    ('truth.maneuvers.direction="prograde"', ["direction", "in-track"]),
    ("truth.maneuvers.speed=1", ["[truth.maneuvers]", "unknown parameter 'speed'"]),
    ('truth.maneuvers.name="hohmann"', ["[truth.maneuvers]", "impulse"]),
    ('measurements.file="obs.csv"', ["[truth.maneuvers]", "real observations"]),
])
def test_bad_maneuver_tables_are_refused_naming_the_table_and_key(item, words):
    with pytest.raises(ConfigError) as err:
        apply_settings(load_scenario("example-1-burn"), [item])
    for w in words:
        assert w in str(err.value)


def test_a_set_vector_over_example_1_burns_delta_v_is_refused_saying_how_to_give_it():
    with pytest.raises(ConfigError) as err:
        apply_settings(load_scenario("example-1-burn"), ["truth.maneuvers.vector_ms=[0, 0, 1]"])
    text = " ".join(str(err.value).split())
    assert "[truth.maneuvers]" in text and "give one form" in text
    assert "A --set cannot remove a key the scenario file writes" in text
    assert """--set 'truth.maneuvers={name="burns", burns=[{t_days=T, vector_ms=[X, Y, Z]}]}'""" in text


def test_example_1_burn_truth_jumps_by_the_burn_and_the_filter_model_stays_ballistic():
    lines: list[str] = []
    ctx, _ = prepare_run(_scenario("example-1-burn"), log=lines.append)
    [imp] = ctx.truth_impulses
    t_b = float(units.days_to_tu(3.62))
    assert imp.t == pytest.approx(t_b, abs=1e-15)
    assert np.linalg.norm(imp.dv) * MS_PER_VU == pytest.approx(1.0, rel=1e-12)
    assert isinstance(ctx.truth_dynamics, ImpulsiveDynamics) and not isinstance(ctx.dynamics, ImpulsiveDynamics)
    assert ctx.truth.impulses == ctx.truth_impulses
    assert any("truth burn 1 at 3.6200 days" in line and "1 m/s" in line and "in-track" in line for line in lines)
    ballistic = ctx.dynamics.dense_trajectory(ctx.truth.x0, 0.0, ctx.scenario.duration)
    eps = 1e-8
    times = [t_b - 0.5, t_b, t_b + eps]
    truth, free = ctx.truth.states_at(times), ballistic.states(times)
    np.testing.assert_allclose(truth[:2], free[:2], atol=1e-10)          # up to the burn: the ballistic truth
    np.testing.assert_allclose(truth[2, :3], free[2, :3], atol=1e-10)    # the position does not jump
    np.testing.assert_allclose(truth[2, 3:] - free[2, 3:], imp.dv, atol=1e-9)
    axes = frame_axes("rtn-moon", truth[1], t_b, ctx.truth_dynamics)
    np.testing.assert_allclose(imp.dv, axes[:, 1] / MS_PER_VU, atol=1e-15)   # in-track, 1 m/s
    later = ctx.truth.states_at([ctx.scenario.duration])[0]
    assert np.linalg.norm(later[:3] - ballistic.states(ctx.scenario.duration)[0, :3]) * units.LU_KM > 10.0


def test_a_smaller_burn_by_set_is_flown_smaller():
    ctx, _ = prepare_run(_scenario("example-1-burn", "truth.maneuvers.delta_v_ms=0.3"))
    assert np.linalg.norm(ctx.truth_impulses[0].dv) * MS_PER_VU == pytest.approx(0.3, rel=1e-12)


def test_a_run_with_a_burn_finishes_and_a_ballistic_run_has_no_impulses():
    res = run_scenario(_scenario("example-1-burn", "duration_days=4.5", "run.predict_every_hours=12"))
    assert len(res.context.truth_impulses) == 1 and res.rows
    assert prepare_run(_scenario("example-1", "duration_days=1.4"))[0].truth_impulses == []


def test_a_burn_after_the_run_is_not_flown():
    lines: list[str] = []
    ctx, _ = prepare_run(_scenario("example-1-burn", "duration_days=1.4"), log=lines.append)
    assert ctx.truth_impulses == [] and not isinstance(ctx.truth_dynamics, ImpulsiveDynamics)
    assert any("no burn inside the run" in line for line in lines)


def test_example_1_maneuver_burns_at_each_apolune():
    ctx, _ = prepare_run(_scenario("example-1-maneuver"))
    imps = ctx.truth_impulses
    assert len(imps) == 2
    np.testing.assert_allclose([units.tu_to_days(i.t) for i in imps], [NRHO_PERIOD_DAYS, 2 * NRHO_PERIOD_DAYS],
                               atol=0.05)
    ballistic = ctx.dynamics.dense_trajectory(ctx.truth.x0, 0.0, ctx.scenario.duration)
    moon = np.array([1 - ctx.dynamics.mu, 0.0, 0.0])
    for k, imp in enumerate(imps):
        assert np.linalg.norm(imp.dv) * MS_PER_VU == pytest.approx(0.1, rel=1e-12)
        before, after = ctx.truth.states_at([imp.t, imp.t + 1e-11])
        np.testing.assert_allclose(after[3:] - before[3:], imp.dv, atol=1e-10)   # 1e-11 TU: the jump alone
        r, v = before[:3] - moon, before[3:]
        assert abs(r @ v) / (np.linalg.norm(r) * np.linalg.norm(v)) < 1e-6      # at apolune
        if k == 0:   # up to the first burn the truth is ballistic
            np.testing.assert_allclose(before, ballistic.states(imp.t)[0], atol=1e-10)
    ctx, _ = prepare_run(_scenario("example-1-maneuver", "truth.maneuvers.delta_v_ms=0.05",
                                   "truth.maneuvers.n_burns=1"))
    assert len(ctx.truth_impulses) == 1
    assert np.linalg.norm(ctx.truth_impulses[0].dv) * MS_PER_VU == pytest.approx(0.05, rel=1e-12)


def test_example_1_dro_burn_flies_example_1_burns_burn_seen_from_the_dro():
    space, ground = load_scenario("example-1-dro-burn"), load_scenario("example-1-burn")
    assert (space.truth_maneuvers.name, space.truth_maneuvers.params) == (ground.truth_maneuvers.name,
                                                                          ground.truth_maneuvers.params)
    assert space.build("sensor").registry_name == "space-telescope"
    assert space.components["iod"].name == "noisy-range"


def test_the_space_maneuver_study_plans_its_false_alarm_runs_and_every_burn_combination(tmp_path):
    from cistrack.studies.study import plan_runs

    _, specs, _ = plan_runs("maneuver-detection-space", tmp_path / "out")
    per_seed = 2 + 5 * 2  # example-1-dro over the response; example-1-dro-burn over dv x response
    assert len(specs) == per_seed * 3 * 20
    assert {s.scenario_name for s in specs if not s.scenario_name.startswith("example-1-dro-burn")} == {
        "example-1-dro[resp=none]", "example-1-dro[resp=inflate]"}
