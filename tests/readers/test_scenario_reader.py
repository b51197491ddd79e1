"""A scenario names the reader of its observation file and the reader's parameters."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import parse_scenario


def _raw(reader):
    return {"name": "obs", "epoch": "2026-03-01T00:00:00Z", "duration_days": 1.0,
            "dynamics": {"name": "cr3bp"}, "sensor": {"name": "ground-telescope"},
            "iod": {"name": "uniform-range"}, "filter": {"name": "ukf"},
            "measurements": {"file": "obs.tdm", "reader": reader}}


def test_scenario_builds_the_named_reader_with_its_parameters():
    scen = parse_scenario(_raw({"name": "csv", "sigma_arcsec": 2.0}), "s.toml")
    assert scen.measurements_reader.name == "csv"
    assert scen.measurements_reader.build(default_registry()).sigma_arcsec == 2.0


def test_an_unknown_reader_parameter_names_the_table_and_key():
    with pytest.raises(ConfigError, match=r"\[measurements.reader\].*'sigma_arcsecs'"):
        parse_scenario(_raw({"name": "csv", "sigma_arcsecs": 2.0}), "s.toml")


def test_an_unknown_reader_lists_the_available_ones():
    with pytest.raises(ConfigError, match="unknown reader 'nope'.*csv"):
        parse_scenario(_raw("nope"), "s.toml")
