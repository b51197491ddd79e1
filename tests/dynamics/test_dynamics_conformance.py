"""The dynamics plugins and catalog orbits pass cistrack's own conformance suite."""
from __future__ import annotations

import pytest

from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.twobody import TwoBody
from cistrack.testing import check_plugin


@pytest.mark.parametrize("component", [CR3BP(), TwoBody()], ids=["cr3bp", "twobody"])
def test_dynamics_plugin_passes_the_conformance_suite(component):
    report = check_plugin(component)
    assert report.passed, str(report)


@pytest.mark.parametrize("name", sorted(ORBITS))
def test_catalog_orbit_passes_the_conformance_suite(name):
    report = check_plugin(ORBITS[name])
    assert report.passed, str(report)
