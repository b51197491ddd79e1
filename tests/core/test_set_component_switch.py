"""``--set filter.name=OTHER`` replaces the file's ``[filter]``, as docs/running.md says, and warns
naming the parameters dropped with it; following the warning's advice keeps those the new filter
takes. The switch had dropped ``n_particles = 200`` without a word, and the SIR filter ran with its
default 10,000 particles (probe H11)."""
from __future__ import annotations

import warnings

import pytest

from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings


@pytest.fixture
def quick():
    return load_scenario("quick").with_overrides({"filter": {"name": "pgm", "n_particles": 200, "n_components": 2}})


def test_switching_the_filter_warns_naming_the_parameters_dropped_and_how_to_keep_them(quick):
    with pytest.warns(UserWarning) as said:
        apply_settings(quick, ["filter.name=sir"])
    (text,) = [str(w.message) for w in said]
    assert text == ("--set filter.name=sir replaces the scenario's [filter] (filter 'pgm'): n_particles = 200, "
                    "n_components = 2 dropped with it; 'sir' takes n_particles too: add --set "
                    "filter.n_particles=200 to keep it")


def test_following_the_advice_keeps_the_parameter(quick):
    with pytest.warns(UserWarning, match=r"n_components = 2 dropped with it \('sir' takes none of them\)"):
        scen = apply_settings(quick, ["filter.name=sir", "filter.n_particles=200"])
    assert scen.components["filter"].name == "sir" and scen.components["filter"].params["n_particles"] == 200


def test_setting_a_parameter_of_the_same_filter_warns_nothing(quick):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scen = apply_settings(quick, ["filter.name=pgm", "filter.n_particles=300"])
    assert scen.components["filter"].params["n_components"] == 2


def test_switching_the_truths_burn_plan_warns_naming_the_burns_keys_dropped():
    """``truth.maneuvers.name=burns`` had dropped the burn's keys without a word, and the run flew
    no burn (probe I8)."""
    with pytest.warns(UserWarning) as said:
        apply_settings(load_scenario("example-1-burn"), ["truth.maneuvers.name=burns"])
    (text,) = [str(w.message) for w in said]
    assert text.startswith("--set truth.maneuvers.name=burns replaces the scenario's [truth.maneuvers] "
                           "(maneuver-plan 'impulse'): t_days = 3.62, delta_v_ms = 1.0, direction = \"in-track\", "
                           "frame = \"rtn-moon\" dropped with it")
