"""Every registered reader passes the conformance suite (round trip, refusals)."""
from __future__ import annotations

import pytest

from cistrack.runs.observation_files import read_observations, reader_for, write_observations
from cistrack.errors import MeasurementError
from cistrack.plugin.registry import load_registry
from cistrack.testing import check_plugin
from cistrack.testing.checks_reader import EPOCH, sample_measurements

_REG = load_registry(autoload_third_party=False)


@pytest.mark.parametrize("name", _REG.names("reader"))
def test_registered_reader_passes_the_conformance_suite(name):
    check_plugin(_REG.get("reader", name).factory)


def test_the_reader_is_chosen_by_suffix(tmp_path):
    ms = sample_measurements("azel")
    p = tmp_path / "obs.csv"
    write_observations(p, ms, EPOCH, registry=_REG)
    back = read_observations(p, EPOCH, registry=_REG)
    assert back.sites.tolist() == ms.sites.tolist()


def test_an_unknown_suffix_asks_for_the_format_and_lists_them(tmp_path):
    with pytest.raises(MeasurementError, match="name the format.*csv"):
        reader_for(tmp_path / "obs.weird", registry=_REG)
