"""A scenario written by ``cistrack init`` runs with another filter after changing only the
filter's name: each component's parameters sit in its own table, [filter.pgm], [filter.ukf],
and only the table of the component named is read."""
from __future__ import annotations

import re

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.scenario.loading import load_scenario, parse_scenario
from cistrack.scenario.settings import apply_settings

SHORT = ["--set", "duration_days=1.5", "--set", "iod.n_particles=300", "--quiet"]


@pytest.fixture
def written(tmp_path, capsys):
    assert main(["init", str(tmp_path / "mine")]) == 0
    capsys.readouterr()
    return tmp_path / "mine.toml"


def _rename_filter(path, name: str) -> None:
    text, n = re.subn(r'^name = "pgm"$', f'name = "{name}"', path.read_text(), flags=re.M)
    assert n == 1
    path.write_text(text)


@pytest.mark.parametrize("filter_name", ["ukf", "enkf"])
def test_changing_only_the_filter_name_of_an_init_file_runs(written, tmp_path, capsys, filter_name):
    _rename_filter(written, filter_name)
    assert main(["run", str(written), "--out", str(tmp_path / "run"), *SHORT]) == 0, capsys.readouterr().err
    assert load_scenario(written).components["filter"].name == filter_name


def test_the_named_filters_own_table_is_read_and_the_others_wait(written):
    text = written.read_text().replace("[filter.ukf]\n", "[filter.ukf]\nalpha = 0.5\n")
    written.write_text(text)
    assert "alpha" not in load_scenario(written).components["filter"].params  # pgm: [filter.ukf] waits
    _rename_filter(written, "ukf")
    params = load_scenario(written).components["filter"].params
    assert params["alpha"] == 0.5 and "n_particles" not in params


def test_switching_with_set_reads_the_new_filters_table(written):
    written.write_text(written.read_text().replace("[filter.ukf]\n", "[filter.ukf]\nalpha = 0.5\n"))
    scen = apply_settings(load_scenario(written), ["filter.name=ukf"])
    assert scen.components["filter"].name == "ukf" and scen.components["filter"].params["alpha"] == 0.5


def _scenario(filter_table: dict) -> dict:
    return {"name": "t", "truth": {"orbit": "nrho-9-2"}, "dynamics": {"name": "cr3bp"},
            "sensor": {"name": "ground-telescope", "measure_range": True}, "schedule": {"name": "paper-example-1"},
            "iod": {"name": "noisy-range", "n_particles": 100}, "filter": filter_table}


def test_the_filter_table_and_the_filters_own_table_merge_where_they_agree():
    scen = parse_scenario(_scenario({"name": "pgm", "n_particles": 200, "pgm": {"n_particles": 200, "n_components": 3}}))
    assert scen.components["filter"].params["n_particles"] == 200
    assert scen.components["filter"].params["n_components"] == 3


def test_one_parameter_given_two_values_in_the_two_tables_is_refused():
    with pytest.raises(ConfigError, match=r"\[filter\] n_particles = 200 and \[filter.pgm\] n_particles = 500"):
        parse_scenario(_scenario({"name": "pgm", "n_particles": 200, "pgm": {"n_particles": 500, "n_components": 3}}))


def test_a_filter_named_key_that_is_not_a_table_is_refused_naming_it():
    with pytest.raises(ConfigError, match=r"\[filter\]: key 'ukf' = 3: .* must be a table, \[filter.ukf\]"):
        parse_scenario(_scenario({"name": "pgm", "ukf": 3}))


def test_a_name_inside_a_filters_own_table_is_refused():
    with pytest.raises(ConfigError, match=r"\[filter.pgm\]: key 'name'"):
        parse_scenario(_scenario({"name": "pgm", "pgm": {"name": "ukf"}}))


def test_a_misspelt_filter_table_is_still_an_unknown_parameter():
    with pytest.raises(ConfigError, match=r"unknown parameter 'ufk' for filter 'pgm'"):
        parse_scenario(_scenario({"name": "pgm", "ufk": {"alpha": 0.5}}))
