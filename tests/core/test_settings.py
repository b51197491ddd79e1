"""--set TABLE.KEY=VALUE: parsed as TOML values, merged into tables, validated like a file."""
from __future__ import annotations

import re

import pytest

from cistrack.errors import ConfigError
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings, merge_settings, parse_settings


def test_values_are_toml_and_bare_words_are_strings():
    assert parse_settings(["filter.n_particles=500", "seed=3", "filter.name=ukf", 'sensor.epoch="x"',
                           "filter.clusterer.n_components=2"]) == \
        {"filter": {"n_particles": 500, "name": "ukf", "clusterer": {"n_components": 2}}, "seed": 3,
         "sensor": {"epoch": "x"}}


@pytest.mark.parametrize("bad", ["filter", "=3", "filter..x=1"])
def test_a_setting_without_key_or_value_is_refused(bad):
    with pytest.raises(ConfigError, match="TABLE.KEY=VALUE"):
        parse_settings([bad])


def test_merging_keeps_other_keys_and_a_new_component_name_replaces_the_table():
    tables = {"filter": {"name": "pgm", "n_particles": 10, "clusterer": {"name": "gmm", "n_components": 3}}}
    assert merge_settings(tables, {"filter": {"clusterer": {"n_components": 2}}}) == \
        {"filter": {"name": "pgm", "n_particles": 10, "clusterer": {"name": "gmm", "n_components": 2}}}
    assert merge_settings(tables, {"filter": {"name": "ukf"}}) == {"filter": {"name": "ukf"}}


def test_applied_settings_are_validated_and_the_error_names_the_setting():
    scen = load_scenario("quick")
    assert apply_settings(scen, ["filter.n_particles=321"]).components["filter"].params["n_particles"] == 321
    with pytest.raises(ConfigError, match=r"\(--set filter.n_particles=-1\).*'n_particles' = -1"):
        apply_settings(scen, ["filter.n_particles=-1"])
    with pytest.raises(ConfigError, match="bogus"):
        apply_settings(scen, ["filter.bogus=1"])


def test_a_setting_in_the_named_components_table_wins_over_the_same_key_in_the_filter_table():
    scen = apply_settings(load_scenario("quick"), ["filter.pgm.n_particles=500"])  # quick's [filter]: 1000
    assert scen.components["filter"].params["n_particles"] == 500


def _quick_text() -> str:
    return open(load_scenario("quick").source).read()


def test_a_setting_in_the_filter_table_wins_over_the_named_components_table(tmp_path):
    path = tmp_path / "s.toml"  # as cistrack init writes it: the parameter in [filter.pgm]
    path.write_text(_quick_text().replace('name = "pgm"\nn_particles = 1000\n', 'name = "pgm"\n')
                    + "\n[filter.pgm]\nn_particles = 1000\n")
    assert load_scenario(str(path)).components["filter"].params["n_particles"] == 1000
    assert apply_settings(load_scenario(str(path)), ["filter.n_particles=300"]).components["filter"].params["n_particles"] == 300


def test_a_file_giving_one_parameter_two_values_is_refused_naming_both(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(_quick_text() + "\n[filter.pgm]\nn_particles = 500\n")
    with pytest.raises(ConfigError, match=r"\[filter\] n_particles = 1000 and \[filter.pgm\] n_particles = 500"):
        load_scenario(str(path))


def test_one_key_given_two_values_by_two_settings_is_refused_naming_both():
    with pytest.raises(ConfigError, match=r"--set filter.n_particles=2000 and --set filter.n_particles=3000: "
                                          r"two values for filter.n_particles"):
        parse_settings(["filter.n_particles=2000", "filter.n_particles=3000"])


def test_a_table_setting_and_a_key_setting_that_disagree_are_refused():
    with pytest.raises(ConfigError, match=r"two values for filter.clusterer.n_init"):
        parse_settings(['filter.clusterer={name="gmm", n_init=2}', "filter.clusterer.n_init=3"])


def test_one_key_given_the_same_value_twice_is_taken():
    assert parse_settings(["filter.n_particles=500", "filter.n_particles=500"]) == {"filter": {"n_particles": 500}}


def test_one_number_written_as_an_integer_and_as_a_float_is_one_value():
    assert parse_settings(["duration_days=1", "duration_days=1.0"]) == {"duration_days": 1.0}


@pytest.mark.parametrize("items", [["filter.n_particles=300", "filter=5"], ["truth.orbit='x'", "truth=1"]])
def test_a_table_set_key_by_key_then_given_a_value_is_refused_naming_both(items):
    first, second = items
    with pytest.raises(ConfigError, match=rf"--set {re.escape(first)} and --set {re.escape(second)}: two values for "
                                          rf"{first.split('.')[0]}; give one"):
        parse_settings(items)


def test_true_and_1_are_two_values():
    with pytest.raises(ConfigError, match="two values for filter.flag"):
        parse_settings(["filter.flag=true", "filter.flag=1"])


def test_api_settings_giving_one_parameter_as_a_table_and_a_dotted_key_are_refused_in_either_order():
    import cistrack as ct

    for settings in ({"filter": {"n_particles": 2000}, "filter.n_particles": 3000},
                     {"filter.n_particles": 3000, "filter": {"n_particles": 2000}}):
        with pytest.raises(ConfigError, match="two values for filter.n_particles"):
            ct.load_scenario("quick", settings=settings)


def test_a_parameter_of_a_default_nested_component_can_be_set_without_its_name():
    scen = apply_settings(load_scenario("quick"), ["filter.clusterer.n_init=2"])  # quick names no clusterer
    clusterer = scen.components["filter"].params["clusterer"]
    assert (clusterer.name, clusterer.params["n_init"]) == ("kmeans", 2)
