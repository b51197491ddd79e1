"""A bad value in a study's ``[overrides]`` is told against the study file and the key, not
against the built-in scenario it was applied to."""
from __future__ import annotations

from pathlib import Path

import pytest

from cistrack.errors import ConfigError
from cistrack.studies.study import plan_runs


def _study(tmp_path: Path, overrides: str) -> Path:
    p = tmp_path / "mine.toml"
    p.write_text(f'name = "mine"\nscenarios = ["quick"]\nseeds = [1]\n\n[overrides]\n{overrides}\n')
    return p


def test_a_bad_component_parameter_names_the_study_file_and_the_setting(tmp_path):
    study = _study(tmp_path, 'filter = { name = "pgm", n_particles = -5 }')
    with pytest.raises(ConfigError) as err:
        plan_runs(study, tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{study}: key 'overrides', setting filter.n_particles = -5")
    assert "applied to scenario 'quick'" in msg and "must be >= 100" in msg


def test_a_bad_top_level_value_names_the_study_file_and_the_key(tmp_path):
    study = _study(tmp_path, "duration_days = -3")
    with pytest.raises(ConfigError, match=rf"^{tmp_path}/mine\.toml: key 'overrides', setting duration_days = -3 "):
        plan_runs(study, tmp_path / "out")


def test_an_unknown_parameter_names_the_study_file_and_the_setting(tmp_path):
    study = _study(tmp_path, "sensor = { nme = 3 }")
    with pytest.raises(ConfigError, match=r"mine\.toml: key 'overrides', setting sensor\.nme = 3 .*unknown parameter"):
        plan_runs(study, tmp_path / "out")


@pytest.mark.parametrize("lists, key, words", [
    ('filters = ["pgm", "nope"]', "filters", "unknown filter 'nope'"),
    ('iod = [{ name = "uniform-range", n_particles = -3 }]', "iod", "'n_particles' = -3"),
])
def test_a_bad_filters_or_iod_entry_names_the_study_file_and_the_entry(tmp_path, lists, key, words):
    study = tmp_path / "mine.toml"
    study.write_text(f'name = "mine"\nscenarios = ["quick"]\nseeds = [1]\n{lists}\n')
    with pytest.raises(ConfigError) as err:
        plan_runs(study, tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{study}: key '{key}', entry ") and "applied to scenario 'quick'" in msg and words in msg


def _with_filters(tmp_path: Path, overrides: str, filters: str = 'filters = ["pgm"]') -> Path:
    p = tmp_path / "mine.toml"
    p.write_text(f'name = "mine"\nscenarios = ["quick"]\nseeds = [1]\n{filters}\n\n[overrides]\n{overrides}\n')
    return p


def test_the_overrides_of_a_filter_apply_under_a_filters_entry_naming_it(tmp_path):
    _, (spec,), _ = plan_runs(_with_filters(tmp_path, "filter = { n_particles = 500 }"), tmp_path / "out")
    assert spec.overrides["filter"] == {"name": "pgm", "n_particles": 500}


def test_a_filters_entrys_own_parameter_wins_over_the_overrides(tmp_path):
    study = _with_filters(tmp_path, "filter = { n_particles = 500 }", 'filters = [{ name = "pgm", n_particles = 800 }]')
    _, (spec,), _ = plan_runs(study, tmp_path / "out")
    assert spec.overrides["filter"]["n_particles"] == 800


def test_a_bad_override_of_a_filter_named_by_a_filters_entry_is_refused_naming_the_overrides(tmp_path):
    study = _with_filters(tmp_path, "filter = { n_particles = -5 }")
    with pytest.raises(ConfigError, match=r"mine\.toml: key 'overrides', setting filter\.n_particles = -5 .*must be >= 100"):
        plan_runs(study, tmp_path / "out")


def _study_text(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "mine.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("lists, value, words", [
    ('filters = ["pgm"]\n', "5", "give a table of the component's parameters, or its name"),
    ('filters = ["pgm"]\n', '"ukf"', "the study's key 'filters' chooses the components"),
    ("", "5", "give a table of the component's parameters, or its name"),
])
def test_a_filter_override_that_is_no_table_is_refused_naming_the_study_file(tmp_path, lists, value, words):
    # with a 'filters' list the entry had silently replaced it: the run flew another filter than written
    study = _study_text(tmp_path, f'name = "mine"\nscenarios = ["quick"]\n{lists}seeds = [1]\n\n'
                                  f"[overrides]\nfilter = {value}\n")
    with pytest.raises(ConfigError, match=rf"^{tmp_path}/mine\.toml: key 'overrides', setting filter = .*{words}"):
        plan_runs(study, tmp_path / "out")


def test_an_unknown_built_in_scenario_names_the_study_file_and_its_key(tmp_path):
    study = _study_text(tmp_path, 'name = "mine"\nscenarios = ["nosuch"]\nseeds = [1]\n')
    with pytest.raises(ConfigError, match=rf"^{tmp_path}/mine\.toml: key 'scenarios', entry 'nosuch': no built-in "
                                          r"scenario 'nosuch'"):
        plan_runs(study, tmp_path / "out")


def test_an_unknown_table_names_the_study_file_and_the_table_as_given(tmp_path):
    """Both had been blamed on the scenario file (probe J4)."""
    study = _study(tmp_path, "foo = { bar = 1 }")
    with pytest.raises(ConfigError) as err:
        plan_runs(study, tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{study}: key 'overrides', setting foo = {{'bar': 1}} (applied to scenario 'quick'")
    assert "unknown key 'foo'" in msg


def test_a_truth_table_that_replaces_the_scenarios_says_what_it_dropped(tmp_path):
    study = _study(tmp_path, 'truth = { maneuvers = { name = "impulse", t_days = 0.5 } }')
    with pytest.raises(ConfigError) as err:
        plan_runs(study, tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{study}: key 'overrides', setting truth = {{'maneuvers': ") and "[truth] needs 'orbit'" in msg
    assert "the override replaces the scenario's whole [truth] table, so its orbit = " in msg
    assert "in the override's truth table too" in msg


def test_a_seed_in_the_overrides_is_refused_naming_the_studys_seeds(tmp_path):
    """It had been dropped without a word: the runs used the study's seeds (probe J9)."""
    study = _study(tmp_path, "seed = 5")
    with pytest.raises(ConfigError) as err:
        plan_runs(study, tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{study}: key 'overrides', setting seed = 5: a study's runs take their seeds from its key "
                          "'seeds'") and "give seeds = [5] instead" in msg


def test_a_missing_scenario_file_names_where_it_was_looked_for(tmp_path, monkeypatch):
    """Probe N: 'scenario file not found: nope.toml' had said neither folder it was looked for in."""
    (tmp_path / "studies").mkdir()
    study = _study_text(tmp_path / "studies", 'name = "mine"\nscenarios = ["nope.toml"]\nseeds = [1]\n')
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=rf"entry 'nope.toml': scenario file not found: neither "
                                          rf"{tmp_path}/studies/nope\.toml \(beside the study file\) nor "
                                          rf"{tmp_path}/nope\.toml \(from the working folder\) exists"):
        plan_runs(study, tmp_path / "out")
