"""An error in the Python API's ``settings`` speaks of the argument it was given, on one line:
lists had been quoted back as multi-line TOML (``'[\\n    1,\\n    2,\\n]'``), and errors named
``--set``, which a Python caller never gave."""
from __future__ import annotations

import pytest

import cistrack as ct
from cistrack.errors import ConfigError


def test_a_list_setting_is_quoted_on_one_line():
    with pytest.raises(ConfigError) as err:
        ct.load_scenario("quick", settings={"filter": {"n_particles": [1, 2]}})
    assert "settings['filter.n_particles']=[1, 2])" in str(err.value) and "\n" not in str(err.value)


def test_a_list_of_tables_is_written_as_inline_tables():
    scen = ct.load_scenario("example-1-burn", settings={"truth.maneuvers": {
        "name": "burns", "burns": [{"t_days": 1.0, "delta_v_ms": 0.5}]}})
    assert scen.truth_maneuvers.params["burns"] == [{"t_days": 1.0, "delta_v_ms": 0.5}]


def test_an_unknown_fit_setting_is_named_as_a_key_of_settings_not_a_set_option(tmp_path):
    with pytest.raises(ConfigError, match=r"^settings\['fit\.lvo'\]: unknown fit setting; known: "):
        ct.fit(_observations(), out=tmp_path / "fit", progress=False, settings={"fit.lvo": 2})


def test_an_unknown_table_of_a_fit_says_with_settings(tmp_path):
    with pytest.raises(ConfigError, match=r"^cistrack fit \(fit-defaults\.toml with settings\): top level: "
                                          r"unknown key 'fitt'"):
        ct.fit(_observations(), out=tmp_path / "fit", progress=False, settings={"fitt": 2})


def _observations():
    """A small observation file of the built-in scenario ``real-data``'s object."""
    from cistrack.scenario.loading import load_scenario

    return load_scenario("real-data").measurements_file
