"""Study reports name each scenario's observers (cistrack.studies.architectures)."""
from __future__ import annotations

from cistrack.scenario.loading import load_scenario
from cistrack.studies.architectures import scenario_architecture


def test_a_ground_scenario_is_named_by_its_sensor_and_site():
    assert scenario_architecture(load_scenario("example-1").raw) == "ground-telescope at (30.62, -96.34) deg"


def test_a_space_scenario_is_named_by_its_orbit_and_phase():
    assert scenario_architecture(load_scenario("example-1-l2").raw) == "space-telescope on l2-lyapunov at phase 0.5"


def test_a_network_names_every_observer_by_its_key():
    assert scenario_architecture(load_scenario("example-1-ground-space").raw) == (
        "texas: ground-telescope (radec) at (30.62, -96.34) deg + dro: space-telescope on dro-2-1 at phase 0.5")
