"""The space telescope's start keys: ``orbit`` and ``state_km`` are exclusive, and ``state_epoch``
lies within a stated span before the scenario epoch."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError, ParameterError
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.sensors.space_telescope import SpaceTelescope
from cistrack.scenario.loading import load_scenario
from cistrack.units import LU_KM, VU_KMS

DRO = np.array(ORBITS["dro-2-1"].state)
DRO_KM = list(np.concatenate([DRO[:3] * LU_KM, DRO[3:] * VU_KMS]))
MOVED_KM = [DRO_KM[0] + 5000.0, *DRO_KM[1:]]


def test_the_default_orbit_named_with_a_state_is_refused_naming_both_keys():
    with pytest.raises(ParameterError, match=r"'orbit' = 'dro-2-1'.*'state_km'.*exclusive"):
        SpaceTelescope(orbit="dro-2-1", state_km=MOVED_KM)


def test_a_scenario_giving_both_keys_is_refused_naming_both():
    with pytest.raises(ConfigError, match=r"example-1-dro\.toml.*'orbit'.*'state_km'.*exclusive"):
        load_scenario("example-1-dro", overrides={"sensor": {"state_km": MOVED_KM}}).build("sensor")


def test_state_km_alone_flies_the_state():
    sensor = SpaceTelescope(state_km=MOVED_KM)
    assert sensor.orbit == ""
    assert np.isclose(sensor.observer_states(0.0)[0] * LU_KM, MOVED_KM[0])


def test_neither_key_flies_the_default_catalog_orbit():
    sensor = SpaceTelescope()
    assert sensor.orbit == "dro-2-1"
    assert np.allclose(sensor.observer_states(0.0), DRO, atol=1e-12)


def test_a_state_epoch_centuries_before_the_epoch_is_refused_naming_the_key_value_and_span():
    with pytest.raises(ParameterError, match=r"'state_epoch' = '1800-01-01T00:00:00Z'.*2024-12-31T00:00:00Z.*"
                                             r"2026-01-01T00:00:00Z.*366 days"):
        SpaceTelescope(state_km=DRO_KM, state_epoch="1800-01-01T00:00:00Z", epoch="2026-01-01T00:00:00Z")


def test_a_state_epoch_within_the_span_is_taken():
    sensor = SpaceTelescope(state_km=DRO_KM, state_epoch="2025-06-01T00:00:00Z", epoch="2026-01-01T00:00:00Z")
    assert np.all(np.isfinite(sensor.observer_states(0.0)))
