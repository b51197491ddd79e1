"""Scenario files are validated before anything runs; every error names file, table and key."""
from __future__ import annotations

from pathlib import Path

import pytest

from cistrack.errors import ConfigError
from cistrack.scenario.loading import builtin_scenarios, load_scenario

GOOD = """
name = "t"
epoch = "2026-01-01T00:00:00Z"
seed = 3
duration_days = 2.0
[truth]
orbit = "nrho-9-2"
[dynamics]
name = "cr3bp"
[sensor]
name = "ground-telescope"
[schedule]
name = "paper-example-1"
[iod]
name = "noisy-range"
[filter]
name = "pgm"
n_particles = 500
[filter.clusterer]
name = "kmeans"
"""


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "scenario.toml"
    p.write_text(text)
    return p


def _error(tmp_path, text) -> str:
    p = _write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_scenario(p)
    msg = str(info.value)
    assert str(p) in msg, msg
    return msg


def test_a_valid_scenario_builds_every_component(tmp_path):
    scen = load_scenario(_write(tmp_path, GOOD))
    assert scen.seed == 3 and scen.components["filter"].name == "pgm"
    assert type(scen.build("filter")).__name__.lower().startswith("pgm")
    assert scen.build("filter").clusterer.registry_name == "kmeans"


def test_the_scenario_epoch_is_handed_to_the_sensor(tmp_path):
    scen = load_scenario(_write(tmp_path, GOOD.replace("2026-01-01T00:00:00Z", "2027-03-04T05:06:07Z")))
    assert scen.build("sensor").epoch.startswith("2027-03-04T05:06:07")


def test_unknown_plugin_name_lists_available_and_closest(tmp_path):
    msg = _error(tmp_path, GOOD.replace('name = "pgm"', 'name = "pgn"'))
    assert "[filter]" in msg and "available:" in msg and "pgm" in msg and "Did you mean 'pgm'?" in msg


def test_unknown_parameter_names_table_and_key_and_the_allowed_ones(tmp_path):
    msg = _error(tmp_path, GOOD.replace("n_particles = 500", "n_particle = 500"))
    assert "[filter]" in msg and "'n_particle'" in msg and "allowed:" in msg and "Did you mean 'n_particles'?" in msg


def test_ill_typed_parameter_names_table_key_and_expected_type(tmp_path):
    msg = _error(tmp_path, GOOD.replace("n_particles = 500", 'n_particles = "many"'))
    assert "[filter]" in msg and "'n_particles'" in msg and "expected an integer" in msg


def test_out_of_range_parameter_value_is_reported_with_its_table(tmp_path):
    msg = _error(tmp_path, GOOD.replace('name = "ground-telescope"', 'name = "ground-telescope"\nsigma_arcsec = -1.0'))
    assert "[sensor]" in msg and "sigma_arcsec" in msg and "[1e-06, 648000] arcsec" in msg


def test_unknown_nested_component_lists_the_clusterers(tmp_path):
    msg = _error(tmp_path, GOOD.replace('name = "kmeans"', 'name = "kmean"'))
    assert "[filter.clusterer]" in msg and "Did you mean 'kmeans'?" in msg


def test_unknown_top_level_key_is_reported(tmp_path):
    msg = _error(tmp_path, GOOD.replace("seed = 3", "seed = 3\nsed = 4"))
    assert "unknown key 'sed'" in msg


def test_missing_component_table_is_reported(tmp_path):
    msg = _error(tmp_path, GOOD.replace('[iod]\nname = "noisy-range"\n', ""))
    assert "missing table [iod]" in msg


def test_unknown_orbit_lists_the_catalog(tmp_path):
    msg = _error(tmp_path, GOOD.replace('orbit = "nrho-9-2"', 'orbit = "nrho-9-3"'))
    assert "[truth]" in msg and "nrho-9-2" in msg


def test_bad_epoch_is_reported(tmp_path):
    msg = _error(tmp_path, GOOD.replace("2026-01-01T00:00:00Z", "yesterday"))
    assert "'epoch'" in msg and "ISO-8601" in msg


def test_an_epoch_given_as_a_toml_date_without_a_time_says_which_forms_are_taken(tmp_path):
    """It had been quoted as datetime.date(2026, 1, 1), 'expected str or datetime' (probe H13)."""
    msg = _error(tmp_path, GOOD.replace('"2026-01-01T00:00:00Z"', "2026-01-01"))
    assert "'epoch' = 2026-01-01 is a date without a time of day" in msg
    assert 'epoch = "2026-01-01T00:00:00Z"' in msg and "datetime.date" not in msg


def test_sensor_table_may_not_set_the_epoch(tmp_path):
    msg = _error(tmp_path, GOOD.replace('name = "ground-telescope"', 'name = "ground-telescope"\nepoch = "2026-01-01T00:00:00Z"'))
    assert "[sensor]" in msg and "top-level 'epoch'" in msg


def test_toml_syntax_error_names_the_file(tmp_path):
    msg = _error(tmp_path, GOOD + "\n[filter\n")
    assert "not valid TOML" in msg


def test_truth_state_must_have_six_numbers(tmp_path):
    msg = _error(tmp_path, GOOD.replace('orbit = "nrho-9-2"', "state_km = [1.0, 2.0]"))
    assert "'state_km'" in msg and "6 finite numbers" in msg


def test_every_builtin_scenario_validates():
    names = builtin_scenarios()
    assert {"example-1", "example-2", "example-3", "mirror-orbit", "quick"} <= set(names)
    for name in names:
        assert load_scenario(name).name == name


def test_unknown_builtin_scenario_suggests_the_closest():
    with pytest.raises(ConfigError, match="Did you mean 'example-1'"):
        load_scenario("example1")


def _example1_with(n: int):
    from cistrack.scenario.loading import load_scenario

    return load_scenario("example-1").with_overrides({"filter": {"n_particles": n}, "iod": {"n_particles": n}})


def test_ten_million_particles_over_one_period_pass_the_memory_check_in_16_gib(monkeypatch):
    """Issue 15: 10,000,000 particles over one period fit in 16 GB (measured peak of a 1e6 run:
    404 bytes per particle; the IOD's oversampling no longer multiplies its memory)."""
    import cistrack.scenario.limits as limits

    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 16 * 2 ** 30)
    assert _example1_with(10_000_000).components["filter"].params["n_particles"] == 10_000_000


def test_a_hundred_million_particles_are_refused_in_16_gib_naming_the_key(monkeypatch):
    import cistrack.scenario.limits as limits
    from cistrack.errors import ConfigError

    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 16 * 2 ** 30)
    with pytest.raises(ConfigError, match=r"n_particles.*memory"):
        _example1_with(100_000_000)


@pytest.mark.parametrize("settings, words", [
    (["schedule.name=every", "schedule.end_hours=-5"], "parameter 'end_hours' = -5.0"),
    (["duration_days=1e400"], "must be a finite number > 0"),
    (["iod.name=tracklet-ranging", "iod.dynamics=foo"], "parameter 'dynamics' = 'foo' is invalid: must be one of"),
])
def test_a_bad_setting_is_named_as_the_user_wrote_it(settings, words):
    from cistrack.scenario.settings import apply_settings

    with pytest.raises(ConfigError) as exc:
        apply_settings(load_scenario("quick"), settings)
    assert words in str(exc.value)


def test_a_leap_second_epoch_is_refused_as_the_observation_readers_refuse_one(tmp_path):
    msg = _error(tmp_path, GOOD.replace('epoch = "2026-01-01T00:00:00Z"', 'epoch = "2016-12-31T23:59:60Z"'))
    assert "key 'epoch' = '2016-12-31T23:59:60Z' is a leap second (second 60): leap-second time tags are not " \
           "supported" in msg
