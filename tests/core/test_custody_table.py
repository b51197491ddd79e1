"""The scenario's [custody] table sets every verdict threshold of CustodyRule and refuses bad
values naming the file, the table and the key (issue 16: degenerate_ess and the other thresholds
were fixed in code)."""
from __future__ import annotations

import math

import pytest

from cistrack.evaluation.custody import CustodyRule
from cistrack.scenario.custody_table import CUSTODY_KEYS, custody_rule
from cistrack.errors import ConfigError
from cistrack.scenario.loading import load_scenario


def test_every_field_of_the_custody_rule_is_a_key_of_the_table():
    from dataclasses import fields

    assert CUSTODY_KEYS == {f.name for f in fields(CustodyRule)}


def test_an_empty_table_keeps_the_rule_defaults():
    assert custody_rule({}, "s.toml") == CustodyRule()


@pytest.mark.parametrize("key, value", [("degenerate_ess", 3.0), ("collapse_sigma_km", 0.0),
                                        ("diverged_error_km", 500.0), ("diverged_nees", math.inf),
                                        ("max_earth_distance_km", 1e7), ("precision_km", 20),
                                        ("hdr_consecutive", 3), ("loglik_threshold", -50.0),
                                        ("diverged_nis", 500.0), ("diverged_nis_updates", 5)])
def test_each_threshold_is_settable_from_the_table(key, value):
    assert getattr(custody_rule({key: value}, "s.toml"), key) == value


def test_a_scenario_setting_reaches_the_run_rule():
    scen = load_scenario("quick").with_overrides({"custody": {"degenerate_ess": 2.5, "collapse_sigma_km": 0.01}})
    assert (scen.custody.degenerate_ess, scen.custody.collapse_sigma_km) == (2.5, 0.01)


@pytest.mark.parametrize("key, value, words", [
    ("degenerate_ess", -1.0, ">= 0"), ("degenerate_ess", math.nan, ">= 0"), ("degenerate_ess", math.inf, "finite"),
    ("collapse_sigma_km", "small", "expected int or float"), ("max_earth_distance_km", 0.0, "> 0"),
    ("diverged_nees", -5, ">= 0"), ("diverged_error_km", True, "expected int or float"),
    ("precision_km", math.inf, "finite"), ("hdr_threshold", 1.0, "(0, 1)"), ("diverged_nis", 0.0, "> 0"),
    ("diverged_nis_updates", 0, ">= 1"), ("diverged_nis_updates", 2.5, "expected int")])
def test_a_bad_value_is_refused_naming_the_file_table_key_and_what_is_allowed(key, value, words):
    with pytest.raises(ConfigError) as err:
        custody_rule({key: value}, "s.toml")
    msg = str(err.value)
    assert msg.startswith("s.toml: [custody]: key ") and repr(key) in msg and words in msg, msg


def test_an_unknown_key_lists_the_allowed_ones_and_the_closest():
    with pytest.raises(ConfigError, match=r"unknown key 'degenerate_es'.*Did you mean 'degenerate_ess'"):
        custody_rule({"degenerate_es": 3.0}, "s.toml")
