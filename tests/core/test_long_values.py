"""A message quotes a value at most about 60 characters long: a longer one is cut, with its
length said, so that no error grows with what the user gave (a 100,000-character ``--set``)."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError, quoted
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings

LONG = "x" * 100_000


def test_a_long_string_is_quoted_by_its_start_and_its_length():
    assert quoted(LONG) == f"'{'x' * 40}...' (100,000 characters)"
    assert quoted("ukf") == "'ukf'"


@pytest.mark.parametrize("item", [f"name={LONG}", f"dynamics.name={LONG}", f"epoch={LONG}", f"seed={LONG}",
                                  f"filter.n_particles={LONG}", f"sensor.{LONG}=1", f"filter.n_particles=[{'1,' * 50_000}1]"])
def test_an_error_about_a_long_setting_is_short(item):
    with pytest.raises(ConfigError) as err:
        apply_settings(load_scenario("quick"), [item])
    assert len(str(err.value)) < 700 and "100,0" in str(err.value)


def test_predict_site_error_quotes_a_long_code_shortened():
    from cistrack.cli.predict_command import _site

    with pytest.raises(ConfigError) as err:
        _site(LONG)
    assert len(str(err.value)) < 400 and "(100,000 characters)" in str(err.value)


def test_an_error_about_a_long_sensors_key_names_its_table_shortened():
    raw = load_scenario("example-1-ground-space").raw
    with pytest.raises(ConfigError) as err:
        load_scenario("example-1-ground-space", overrides={"sensors": {"x" * 5000: raw["sensors"]["dro"]}})
    assert len(str(err.value)) < 700 and f"[sensors.'{'x' * 40}...' (5,000 characters)]" in str(err.value)


def test_two_long_designations_that_differ_only_at_their_end_are_shown_apart():
    """Designations differing after character 60 had printed alike, so a verdict could not be told
    from the other object's (probe M10)."""
    from cistrack.errors import clipped

    a, b = "D" * 80 + "-one", "D" * 80 + "-two"
    assert clipped(a) != clipped(b) and clipped(a).endswith("-one (84 characters)")
    assert len(clipped(a)) < 70 and clipped("C/2026 A1") == "C/2026 A1"
