"""A sensor's bad measurements are blamed on the sensor by the name it was registered under (a
registered subclass of a built-in sensor by its own name), with the time and the component of the
first bad value: "measurement values or sigmas contain NaN or infinity" had named nothing."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry, load_registry
from cistrack.plugins.filters.ukf import UKFFilter
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.testing.suite import label


class NanSensor(GroundTelescope):
    """A ground telescope whose measure() gives NaN for the first state."""

    def measure(self, states, t):
        z = np.array(super().measure(states, t), dtype=float)
        z[0] = np.nan
        return z


def test_a_measurement_set_with_nan_names_the_first_bad_measurement_its_time_and_component():
    with pytest.raises(MeasurementError, match=r"NaN or infinity: measurement 1 \(t = 0\.2 TU = 0\.8684 d\), "
                                               r"elevation: value nan, sigma 1$"):
        MeasurementSet([0.1, 0.2], [[1.0, 1.0], [1.0, np.nan]], np.ones((2, 2)), ("azimuth", "elevation"))


def test_a_measurement_set_with_a_sigma_not_above_zero_names_it():
    with pytest.raises(MeasurementError, match=r"sigmas must be > 0: measurement 0 \(t = 0\.1 TU = 0\.4342 d\), "
                                               r"azimuth: value 1, sigma -1e-06$"):
        MeasurementSet([0.1, 0.2], np.ones((2, 2)), [[-1e-6, 1.0], [1.0, 1.0]], ("azimuth", "elevation"))


def test_a_sensor_simulating_nan_in_a_run_is_named_with_its_distribution():
    reg = load_registry(autoload_third_party=False)
    reg.add("sensor", "h-nansensor", NanSensor, "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg, overrides={"sensor": {"name": "h-nansensor"}, "filter": {"name": "ukf"}})
    with pytest.raises(MeasurementError, match=r"^sensor 'h-nansensor' \(hplug 0\.1\): simulate\(\) gave measurement "
                                               r"values or sigmas contain NaN or infinity: measurement 0 \(t = "):
        run_scenario(scen, seed=1, registry=reg)


def test_a_registered_subclass_of_a_built_in_sensor_is_called_by_its_own_name():
    class Mine(GroundTelescope):
        """A ground telescope under another name."""

    Registry().add("sensor", "h-mine", Mine, "hplug", "0.1", "hplug")
    with pytest.raises(MeasurementError, match=r"^sensor 'h-mine': angles contain NaN"):
        Mine().line_of_sight(np.full((1, 2), np.nan), 0.0)


def test_the_conformance_suite_calls_an_unregistered_subclass_by_its_class_name():
    class MyUKF(UKFFilter):
        """A UKF of one's own, not registered."""

    load_registry(autoload_third_party=False)  # the built-in UKF registered as 'ukf'
    assert label(MyUKF) == "MyUKF"
