"""The dynamics plugins and catalog orbits pass cistrack's own conformance suite."""
from __future__ import annotations

import pytest

from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.twobody import TwoBody
from cistrack.testing import check_plugin
from cistrack.testing.check_results import ConformanceError


@pytest.mark.parametrize("component", [CR3BP(), TwoBody()], ids=["cr3bp", "twobody"])
def test_dynamics_plugin_passes_the_conformance_suite(component):
    report = check_plugin(component)
    assert report.passed, str(report)


@pytest.mark.parametrize("name", sorted(ORBITS))
def test_catalog_orbit_passes_the_conformance_suite(name):
    report = check_plugin(ORBITS[name])
    assert report.passed, str(report)


def test_the_ephemeris_model_with_its_integrated_sensitivity_passes_the_conformance_suite():
    report = check_plugin(EphemerisDynamics(epoch="2026-01-01T00:00:00Z", area_to_mass_m2_kg=0.01))
    assert report.passed, str(report)


class FlippedSensitivity(EphemerisDynamics):
    """The ephemeris model with its area-to-mass sensitivity of the wrong sign."""

    def propagate_with_sensitivity(self, state, t0, times, name):
        states, stms, sens = super().propagate_with_sensitivity(state, t0, times, name)
        return states, stms, -sens


def test_a_sensitivity_of_the_wrong_sign_fails_the_conformance_suite():
    with pytest.raises(ConformanceError) as exc:
        check_plugin(FlippedSensitivity(epoch="2026-01-01T00:00:00Z"))
    assert [r.name for r in exc.value.results if not r.passed] == ["sensitivities_match_differences"]
