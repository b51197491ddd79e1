"""A third party's IOD that raises its own exception, or returns something other than what
``IODMethod.estimate`` promises, stops the run before its first filter step with an IODError naming
the IOD and its distribution (the command's exit status 2), never a traceback."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import IODError
from cistrack.interfaces.iod import IODMethod
from cistrack.model.belief import ParticleCloud
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


class WrongIOD(IODMethod):
    """An IOD giving ``how`` instead of a cloud at the last measurement: "array" (its states as a
    bare array), "raise" (its own ZeroDivisionError), "late" (a cloud 1000 TU after the last
    measurement), "nan" (a cloud with a NaN state), "width" (states of 4 components), "one" (a cloud
    of 1 particle)."""

    def __init__(self, how: str = "array") -> None:
        self.how = how

    def estimate(self, measurements, sensor, rng):
        t = float(measurements.times[-1])
        states = np.array([1.02, 0.0, -0.18, 0.0, -0.1, 0.0]) + 1e-4 * rng.standard_normal((100, 6))
        if self.how == "array":
            return states
        if self.how == "raise":
            raise ZeroDivisionError("division by zero in the plugin")
        if self.how == "nan":
            states[3, 2] = np.nan
            return ParticleCloud(states, t)
        if self.how == "width":
            return ParticleCloud(states[:, :4], t)
        if self.how == "one":
            return ParticleCloud(states[:1], t)
        return ParticleCloud(states, t + 1000.0)


def _run(how: str):
    reg = load_registry(autoload_third_party=False)
    reg.add("iod", "h-iod", WrongIOD, "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg, overrides={"duration_days": 2.0, "iod": {"name": "h-iod", "how": how}})
    return run_scenario(scen, seed=1, registry=reg)


def test_an_iod_returning_an_array_is_an_iod_error_naming_it_and_what_it_must_return():
    with pytest.raises(IODError, match=r"^iod 'h-iod' \(hplug 0\.1\): estimate\(\) returned ndarray, not a "
                                       r"ParticleCloud"):
        _run("array")


def test_an_iod_raising_its_own_exception_is_an_iod_error_naming_it_and_the_exception():
    with pytest.raises(IODError, match=r"^iod 'h-iod' \(hplug 0\.1\): estimate\(\) raised ZeroDivisionError: "
                                       r"division by zero in the plugin$"):
        _run("raise")


def test_an_iod_cloud_dated_after_its_measurements_is_an_iod_error_naming_it_and_their_times():
    with pytest.raises(IODError, match=r"^iod 'h-iod' \(hplug 0\.1\): estimate\(\) returned a cloud at t = 4,343\.993 d, "
                                       r"outside the 17 measurements it was given \(0\.816 d to 1\.991 d\); an IOD's "
                                       r"cloud is at the epoch of the last measurement it used$"):
        _run("late")


@pytest.mark.parametrize("how, what", [("nan", r"whose states are not all finite \(1 of 100 hold NaN or inf\)"),
                                       ("width", r"with states of shape \(100, 4\)"),
                                       ("one", r"of 1 particle; a filter starts from a spread of states")])
def test_an_iod_cloud_the_filter_cannot_start_from_is_an_iod_error_naming_the_iod(how, what):
    with pytest.raises(IODError, match=rf"^iod 'h-iod' \(hplug 0\.1\): estimate\(\) returned a cloud {what}"):
        _run(how)
