"""Maneuver plans ``impulse``, ``burns`` and ``station-keeping``: local frames, resolution along
the truth flown with the earlier burns, apolune search and parameter validation."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError, ParameterError
from cistrack.interfaces.maneuvers import Impulse
from cistrack.plugins.maneuvers.local_frames import frame_axes
from cistrack.plugins.maneuvers.plans import BurnsPlan, ImpulsePlan, StationKeepingPlan
from cistrack.propagation.impulses import MS_PER_VU, ImpulsiveDynamics, describe_impulse, fly_plan

NRHO = np.array([1.0221, 0.0, -0.1821508, 0.0, -0.10342725, 0.0])
NRHO_PERIOD = 1.5121455320848902      # TU
SPAN = 2.2                            # TU


@pytest.fixture(scope="module")
def cr3bp(registry):
    return registry.create("dynamics", "cr3bp")


def _state_at(dyn, t, earlier=()):
    d = ImpulsiveDynamics(dyn, list(earlier)) if earlier else dyn
    return d.propagate(NRHO, 0.0, t).final[0]


def test_the_plans_are_registered(registry):
    assert {"impulse", "burns", "station-keeping"} <= set(registry.names("maneuver-plan"))


@pytest.mark.parametrize("frame", ["rtn-moon", "rtn-earth", "vnb"])
def test_local_frames_are_orthonormal_and_right_handed(cr3bp, frame):
    m = frame_axes(frame, NRHO + np.array([0.01, 0.02, 0.0, 0.03, 0.0, 0.05]), 0.0, cr3bp)
    np.testing.assert_allclose(m.T @ m, np.eye(3), atol=1e-14)
    assert np.linalg.det(m) == pytest.approx(1.0)


def test_rtn_and_vnb_axes_by_their_definitions(cr3bp):
    x = NRHO + np.array([0.0, 0.01, 0.0, 0.02, 0.0, 0.0])
    moon = np.array([1 - cr3bp.mu, 0.0, 0.0])
    r, v = x[:3] - moon, x[3:]
    rtn = frame_axes("rtn-moon", x, 0.0, cr3bp)
    np.testing.assert_allclose(rtn[:, 0], r / np.linalg.norm(r), atol=1e-15)
    h = np.cross(r, v)
    np.testing.assert_allclose(rtn[:, 2], h / np.linalg.norm(h), atol=1e-15)
    assert rtn[:, 1] @ v > 0 and abs(rtn[:, 1] @ r) < 1e-15           # in-track: along the motion, normal to r
    vnb = frame_axes("vnb", x, 0.0, cr3bp)
    np.testing.assert_allclose(vnb[:, 0], v / np.linalg.norm(v), atol=1e-15)
    earth = frame_axes("rtn-earth", x, 0.0, cr3bp)[:, 0]
    re = x[:3] - np.array([-cr3bp.mu, 0.0, 0.0])
    np.testing.assert_allclose(earth, re / np.linalg.norm(re), atol=1e-15)


@pytest.mark.parametrize("direction, column, sign", [("in-track", 1, 1), ("anti-in-track", 1, -1), ("radial", 0, 1),
                                                     ("anti-radial", 0, -1), ("cross-track", 2, 1),
                                                     ("anti-cross-track", 2, -1)])
def test_an_impulse_along_each_direction_of_rtn_moon(cr3bp, direction, column, sign):
    t_days = 3.0
    [imp] = ImpulsePlan(t_days=t_days, delta_v_ms=2.0, direction=direction).impulses(cr3bp, NRHO, 0.0, SPAN)
    t = float(units.days_to_tu(t_days))
    assert imp.t == pytest.approx(t)
    axes = frame_axes("rtn-moon", _state_at(cr3bp, t), t, cr3bp)
    np.testing.assert_allclose(imp.dv, sign * axes[:, column] * 2.0 / MS_PER_VU, atol=1e-15)
    assert direction in imp.label


def test_a_vector_in_a_frame_and_in_the_synodic_frame(cr3bp):
    t = float(units.days_to_tu(2.0))
    [imp] = ImpulsePlan(t_days=2.0, vector_ms=[0.3, -0.4, 1.2], frame="vnb").impulses(cr3bp, NRHO, 0.0, SPAN)
    axes = frame_axes("vnb", _state_at(cr3bp, t), t, cr3bp)
    np.testing.assert_allclose(imp.dv * MS_PER_VU, axes @ [0.3, -0.4, 1.2], atol=1e-12)
    [syn] = ImpulsePlan(t_days=2.0, vector_ms=[0.3, -0.4, 1.2], frame="synodic").impulses(cr3bp, NRHO, 0.0, SPAN)
    np.testing.assert_allclose(syn.dv * MS_PER_VU, [0.3, -0.4, 1.2], atol=1e-12)


def test_a_burn_outside_the_span_is_not_flown(cr3bp):
    assert ImpulsePlan(t_days=20.0).impulses(cr3bp, NRHO, 0.0, SPAN) == []
    dyn, imps = fly_plan(ImpulsePlan(t_days=20.0), cr3bp, NRHO, 0.0, SPAN)
    assert dyn is cr3bp and imps == []


def test_burns_are_resolved_along_the_truth_with_the_earlier_burns(cr3bp):
    plan = BurnsPlan(burns=[{"t_days": 6.0, "delta_v_ms": 0.5, "direction": "radial", "label": "late"},
                            {"t_days": 2.0, "delta_v_ms": 3.0}])
    first, second = plan.impulses(cr3bp, NRHO, 0.0, SPAN + 1)
    assert first.t < second.t and first.label.startswith("burn 1") and second.label.startswith("late")  # in time order
    t2 = second.t
    axes_with = frame_axes("rtn-moon", _state_at(cr3bp, t2, [first]), t2, cr3bp)
    np.testing.assert_allclose(second.dv, axes_with[:, 0] * 0.5 / MS_PER_VU, atol=1e-15)
    axes_without = frame_axes("rtn-moon", _state_at(cr3bp, t2), t2, cr3bp)
    assert np.abs(axes_with - axes_without).max() > 1e-4           # the first burn moved the second's frame


def test_station_keeping_burns_at_successive_apolunes(cr3bp):
    t_end = float(units.days_to_tu(13.2))
    imps = StationKeepingPlan(delta_v_ms=0.1, n_burns=3).impulses(cr3bp, NRHO, 0.0, t_end)
    assert len(imps) == 2                                    # a third apolune lies after 13.2 days
    np.testing.assert_allclose([i.t for i in imps], [NRHO_PERIOD, 2 * NRHO_PERIOD], rtol=2e-3)
    flown = ImpulsiveDynamics(cr3bp, imps)
    moon = np.array([1 - cr3bp.mu, 0.0, 0.0])
    for imp in imps:
        assert np.linalg.norm(imp.dv) * MS_PER_VU == pytest.approx(0.1)
        x = flown.propagate(NRHO, 0.0, [imp.t - 1e-3, imp.t, imp.t + 1e-3]).states[:, 0]
        d = np.linalg.norm(x[:, :3] - moon, axis=1)
        assert d[1] >= d[0] and d[1] >= d[2]                 # a maximum of the distance to the Moon
        r, v = x[1, :3] - moon, x[1, 3:]
        assert abs(r @ v) / (np.linalg.norm(r) * np.linalg.norm(v)) < 1e-6
    later = StationKeepingPlan(first_after_days=7.0, n_burns=1).impulses(cr3bp, NRHO, 0.0, t_end)
    # the ballistic truth's second apolune: near the burned one (0.1 m/s moved it by ~0.5 h)
    assert len(later) == 1 and later[0].t == pytest.approx(imps[1].t, abs=1e-3) and later[0].t != imps[1].t


def test_station_keeping_burns_the_run_does_not_reach_are_named_in_the_log(cr3bp):
    lines = []
    fly_plan(StationKeepingPlan(delta_v_ms=0.1, n_burns=5), cr3bp, NRHO, 0.0, float(units.days_to_tu(13.2)),
             lines.append)
    assert any("not flown: station-keeping burns 3 to 5 (the run ends before apolune passage 3)" in line
               for line in lines), lines


def test_station_keeping_that_starts_after_the_run_names_first_after_days(cr3bp):
    lines = []
    fly_plan(StationKeepingPlan(first_after_days=1e9), cr3bp, NRHO, 0.0, SPAN, lines.append)
    assert any("no apolune passage between first_after_days = 1e+09 and the end of the run" in line
               for line in lines), lines


def test_fly_plan_wraps_the_truth_and_says_one_line_per_burn(cr3bp):
    lines = []
    plan = BurnsPlan(burns=[{"t_days": 1.0, "delta_v_ms": 1.0}, {"t_days": 2.0, "delta_v_ms": 0.5}])
    dyn, imps = fly_plan(plan, cr3bp, NRHO, 0.0, SPAN, lines.append)
    assert isinstance(dyn, ImpulsiveDynamics) and dyn.base is cr3bp and len(imps) == 2
    assert len(lines) == 2 and "1.0000 days" in lines[0] and "|dv| = 1 m/s" in lines[0] and "in-track" in lines[0]
    assert describe_impulse(Impulse(1.0, np.zeros(3)), 1).startswith("truth burn 1")


def test_fly_plan_names_each_burn_it_leaves_out_after_the_run(cr3bp):
    lines = []
    plan = BurnsPlan(burns=[{"t_days": 50.0, "delta_v_ms": 0.5}, {"t_days": 1.0, "delta_v_ms": 0.5}])
    dyn, imps = fly_plan(plan, cr3bp, NRHO, 0.0, SPAN, lines.append, where="[truth.maneuvers]")
    assert len(imps) == 1 and len(lines) == 2
    assert "not flown: burn 2: 0.5 m/s in-track (rtn-moon) at 50 days" in lines[1]  # "burn N" numbered in time order


def test_a_burn_just_after_the_run_shows_the_digits_that_put_it_there(cr3bp):
    lines = []
    end_days = float(units.tu_to_days(SPAN))
    fly_plan(ImpulsePlan(t_days=end_days + 1e-9, delta_v_ms=1.0), cr3bp, NRHO, 0.0, SPAN, lines.append)
    assert any(f"at {end_days + 1e-9:.12g} days" in line for line in lines), lines


def test_a_burn_label_with_a_line_break_is_refused():
    with pytest.raises(ParameterError, match="printable characters"):
        ImpulsePlan(t_days=1.0, label="x\ny")


def test_a_burn_label_with_a_right_to_left_override_is_refused_naming_the_character_class():
    with pytest.raises(ParameterError, match="invisible formatting characters such as bidirectional overrides"):
        ImpulsePlan(label="burn\u202e1")


def test_a_burn_label_longer_than_100_characters_is_refused_and_quoted_shortened():
    with pytest.raises(ParameterError, match=r"'L{40}\.\.\.' \(100,000 characters\) is invalid: must be a string of "
                                             r"at most 100 printable characters"):
        ImpulsePlan(label="L" * 100_000)


def test_fly_plan_refuses_a_plan_that_returns_burns_outside_the_span(cr3bp):
    class Bad(ImpulsePlan):
        def impulses(self, dynamics, x0, t0, t_end):
            return [Impulse(t_end + 1.0, np.ones(3) * 1e-4, "late")]

    with pytest.raises(ConfigError, match=r"\[truth.maneuvers\].*outside the run's span"):
        fly_plan(Bad(), cr3bp, NRHO, 0.0, SPAN, where="[truth.maneuvers]")


@pytest.mark.parametrize("cls, params, name", [
    (ImpulsePlan, {"t_days": 0.0}, "t_days"),
    (ImpulsePlan, {"delta_v_ms": -1.0}, "delta_v_ms"),
    (ImpulsePlan, {"direction": "prograde"}, "direction"),
    (ImpulsePlan, {"frame": "lvlh"}, "frame"),
    (ImpulsePlan, {"frame": "synodic"}, "frame"),
    (ImpulsePlan, {"vector_ms": [1.0, 2.0]}, "vector_ms"),
    (ImpulsePlan, {"vector_ms": [1.0, 2.0, float("nan")]}, "vector_ms"),
    (ImpulsePlan, {"delta_v_ms": 1e9}, "delta_v_ms"),
    (ImpulsePlan, {"vector_ms": [1e5, 0.0, 0.0]}, "vector_ms"),
    (ImpulsePlan, {"vector_ms": [0.1, 0.0, 0.0], "delta_v_ms": 5.0, "direction": "radial"}, "vector_ms"),
    (StationKeepingPlan, {"delta_v_ms": 2e4}, "delta_v_ms"),
    (StationKeepingPlan, {"n_burns": 0}, "n_burns"),
    (StationKeepingPlan, {"frame": "synodic"}, "frame"),
    (StationKeepingPlan, {"first_after_days": -1.0}, "first_after_days"),
    (BurnsPlan, {"burns": [{"delta_v_ms": 1.0}]}, "burns[0]"),
    (BurnsPlan, {"burns": [{"t_days": 1.0, "dv": 1.0}]}, "burns[0]"),
    (BurnsPlan, {"burns": [{"t_days": 1.0}, {"t_days": 2.0, "direction": "up"}]}, "burns[1]"),
    (BurnsPlan, {"burns": ["not a table"]}, "burns[0]"),
])
def test_bad_parameters_are_refused_naming_the_parameter_and_what_is_allowed(cls, params, name):
    with pytest.raises(ParameterError) as err:
        cls(**params)
    assert f"'{name}'" in str(err.value)
    if name in ("direction", "frame"):
        assert "rtn-moon" in str(err.value) or "in-track" in str(err.value)


def test_a_vector_whose_size_overflows_is_refused_without_a_numpy_warning():
    """numpy's norm of [1e308, 1e308, 0] had printed "overflow encountered in dot" before the
    refusal (probe I8)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ParameterError, match=r"'vector_ms'.*the burn's size must be at most"):
            ImpulsePlan(t_days=1.0, vector_ms=[1e308, 1e308, 0.0], frame="synodic")


@pytest.mark.parametrize("cls, params", [
    (ImpulsePlan, {"t_days": 1.0, "vector_ms": [0.0, 0.0, 0.2], "delta_v_ms": 1.0}),
    (ImpulsePlan, {"t_days": 1.0, "vector_ms": [0.0, 0.0, 0.2], "direction": "in-track"}),
    (BurnsPlan, {"burns": [{"t_days": 1.0, "vector_ms": [0.0, 0.0, 0.2], "delta_v_ms": 1.0, "direction": "in-track"}]}),
])
def test_both_burn_forms_are_refused_even_at_the_default_values(cls, params):
    """vector_ms with delta_v_ms = 1.0 or direction = "in-track" written out had flown the vector and
    dropped them in silence."""
    with pytest.raises(ParameterError, match="'vector_ms'.* give(s)? it too; give one form"):
        cls(**params)


def test_a_vector_burn_rebuilds_from_its_parameters():
    plan = ImpulsePlan(t_days=1.0, vector_ms=[0.0, 0.0, 0.2])
    assert (plan.delta_v_ms, plan.direction) == (None, None)
    assert ImpulsePlan(**plan.get_params()).burn().vector_ms.tolist() == [0.0, 0.0, 0.2]


@pytest.mark.parametrize("cls", [ImpulsePlan, BurnsPlan, StationKeepingPlan])
def test_the_plans_follow_the_parameter_conventions_and_document_every_parameter(cls):
    """The conformance suite's parameter checks (the suite has no maneuver-plan kind yet) and the
    documentation `cistrack plugins NAME` prints."""
    import re

    from cistrack.plugin.param_docs import param_docs, summary_of
    from cistrack.testing.checks_params import PARAMETER_CHECKS

    plan = cls()
    for _, check in PARAMETER_CHECKS:
        check(plan)
    for p in param_docs(cls):
        assert p.meaning and p.meaning.endswith((".", ")")) and not re.search(r"`", p.meaning), p.name
    assert summary_of(cls).endswith(".") and "`" not in summary_of(cls)


class PluginPlan(ImpulsePlan):
    """A third party's plan whose impulses() does ``how``: "raise" (its own RuntimeError), "nan" (a
    burn with a NaN dv), "width" (a burn with a 4-component dv), "none" (returns None)."""

    how = "raise"

    def impulses(self, dynamics, x0, t0, t_end):
        dv = {"nan": [np.nan, 0.0, 0.0], "width": [0.0, 1e-3, 0.0, 0.0]}.get(self.how)
        if dv is not None:
            return [Impulse(0.5 * (t0 + t_end), np.array(dv), "b")]
        if self.how == "none":
            return None
        raise RuntimeError("cannot plan")


def _scenario_with_plan(how: str):
    from cistrack.plugin.registry import load_registry
    from cistrack.scenario.loading import load_scenario
    from cistrack.scenario.settings import apply_settings

    reg = load_registry(autoload_third_party=False)
    reg.add("maneuver-plan", "h-plan", type("HPlan", (PluginPlan,), {"how": how}), "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg)
    return apply_settings(scen, ["duration_days=1.4", 'truth.maneuvers={name="h-plan"}'], reg), reg


@pytest.mark.parametrize("how, what", [
    ("raise", r"impulses\(\) raised RuntimeError: cannot plan"),
    ("nan", r"impulses\(\) raised ValueError: impulse 'b': dv = \[nan, 0\.0, 0\.0\] is not 3 finite numbers"),
    ("width", r"impulses\(\) raised ValueError: impulse 'b': dv = \[0\.0, 0\.001, 0\.0, 0\.0\] is not 3 finite"),
    ("none", r"impulses\(\) returned NoneType, not a list of Impulse"),
])
def test_a_plugin_plan_that_fails_is_a_config_error_naming_the_table_the_plan_and_its_distribution(how, what):
    from cistrack.runs.pipeline import run_scenario

    scen, reg = _scenario_with_plan(how)
    with pytest.raises(ConfigError, match=r"\[truth\.maneuvers\]: maneuver-plan 'h-plan' \(hplug 0\.1\): " + what):
        run_scenario(scen, seed=1, registry=reg)


def test_a_burn_outside_the_run_is_refused_in_days(cr3bp):
    class Bad(ImpulsePlan):
        def impulses(self, dynamics, x0, t0, t_end):
            return [Impulse(float(units.days_to_tu(20.0)), np.ones(3) * 1e-4, "late")]

    with pytest.raises(ConfigError, match=r"impulse 'late' at t = 20 days lies outside the run's span \(0, 9\.55\d*\] days"):
        fly_plan(Bad(), cr3bp, NRHO, 0.0, SPAN)


def test_a_plan_of_many_burns_is_logged_in_one_summary_line(cr3bp):
    """1,000 burns had written 1,000 lines before the run (and 1,000 more in its summary)."""
    lines = []
    plan = BurnsPlan(burns=[{"t_days": 0.1 * k, "delta_v_ms": 0.01} for k in range(1, 21)])
    _, imps = fly_plan(plan, cr3bp, NRHO, 0.0, SPAN, lines.append)
    assert len(imps) == 20
    assert lines == ["truth burns: 20 from 0.1000 to 2.0000 days, 0.01 to 0.01 m/s each, 0.2 m/s in all "
                     "(one line each for up to 5)"]


def test_a_zero_burn_given_as_minus_zero_says_zero_and_not_flown(cr3bp):
    """It had said "burn: -0 m/s in-track" and an empty synodic direction (+0.000, +0.000, +0.000)."""
    lines = []
    fly_plan(ImpulsePlan(t_days=1.0, delta_v_ms=-0.0), cr3bp, NRHO, 0.0, SPAN, lines.append)
    assert lines == ["truth burn 1 at 1.0000 days: |dv| = 0 m/s, burn: 0 m/s in-track (rtn-moon); a zero burn, "
                     "not flown"]


@pytest.mark.parametrize("t_days", [0.0, 1e-300, 1e-6, -1.0])
def test_a_burn_earlier_than_a_second_after_the_epoch_is_refused_saying_what_is_allowed(t_days):
    """1e-300 days had been taken where 0 was refused, and listed at t_days 0.0 (probe J9)."""
    with pytest.raises(ParameterError, match=r"'t_days'.*must be at least 1 second \(1.1574e-05 days\) after the "
                                             r"scenario epoch"):
        ImpulsePlan(t_days=t_days)


def test_a_burn_a_second_after_the_epoch_is_taken():
    assert ImpulsePlan(t_days=1.0 / 86400.0).t_days == pytest.approx(1.1574e-05, rel=1e-4)
