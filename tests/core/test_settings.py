"""--set TABLE.KEY=VALUE: parsed as TOML values, merged into tables, validated like a file."""
from __future__ import annotations

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
