"""The range model of the kinematic-fit IOD is a component parameter; the paper's three variants
are presets of it with the same names and the same numbers."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.iod.kinematic import KinematicFitIOD
from cistrack.plugins.iod.kinematic_presets import NoisyRangeIOD, UniformRangeIOD, UniformRangeVelocityBoundIOD
from cistrack.plugins.iod.range_priors import NoisyRange, UniformRange
from cistrack.scenario.loading import parse_scenario
from cistrack.testing import check_plugin


@pytest.mark.parametrize("preset, composed", [
    (NoisyRangeIOD(n_particles=300, alpha=0.03),
     KinematicFitIOD(n_particles=300, range_prior=NoisyRange(alpha=0.03))),
    (UniformRangeIOD(n_particles=300),
     KinematicFitIOD(n_particles=300, range_prior=UniformRange())),
    (UniformRangeVelocityBoundIOD(n_particles=300),
     KinematicFitIOD(n_particles=300, range_prior=UniformRange(), max_speed_kms=42.0,
                     oversampling=10.0, max_oversampling=100.0)),
])
def test_each_preset_equals_the_composed_component(scenario, preset, composed):
    ms = scenario.simulate(np.random.default_rng(3))
    a = preset.estimate(ms, scenario.sensor, np.random.default_rng(11))
    b = composed.estimate(ms, scenario.sensor, np.random.default_rng(11))
    np.testing.assert_array_equal(a.states, b.states)
    assert a.meta["range_model"] == b.meta["range_model"] == preset.registry_name


def test_a_scenario_composes_the_range_prior_as_a_nested_table(registry):
    data = {"name": "t", "truth": {"orbit": "nrho-9-2"}, "dynamics": {"name": "cr3bp"},
            "sensor": {"name": "ground-telescope", "measure_range": True}, "schedule": {"name": "paper-example-1"},
            "iod": {"name": "kinematic-fit", "range_prior": {"name": "noisy", "alpha": 0.02}, "max_speed_kms": 30.0},
            "filter": {"name": "ukf"}}
    iod = parse_scenario(data, "<test>", registry).build("iod", registry)
    assert isinstance(iod.range_prior, NoisyRange) and iod.range_prior.alpha == 0.02
    assert iod.range_model == "noisy-range-velocity-bound"


@pytest.mark.parametrize("name", ["noisy", "uniform"])
def test_range_priors_pass_the_conformance_suite(registry, name):
    check_plugin(registry.get("range-prior", name).factory)  # raises, naming the failing checks


class BrokenRange(UniformRange):
    """Uniform ranges, broken by ``how``: "nan" (every second range NaN) or "short" (half the rows)."""

    how, registry_name = "nan", "h-range"

    def draw(self, measured_lu, shape, rng):
        r = np.array(super().draw(measured_lu, shape, rng), dtype=float)
        if self.how == "nan":
            r[::2] = np.nan
            return r
        return r[: shape[0] // 2]


@pytest.mark.parametrize("how, what", [
    ("nan", r"range-prior 'h-range': draw\(\) returned \d+ NaN or infinite ranges of \d+; ranges must be finite"),
    ("short", r"range-prior 'h-range': draw\(\) for shape \(\d+, \d+\) returned ndarray of shape \(\d+, \d+\), not "
              r"ranges \(LU\) that broadcast to \(\d+, \d+\)"),
])
def test_a_range_prior_drawing_nan_or_the_wrong_shape_is_refused_naming_it(scenario, how, what):
    """NaN ranges had been dropped as pruned draws without a word; a wrong shape blamed the IOD."""
    from cistrack.errors import PluginError

    prior = BrokenRange()
    prior.how = how
    ms = scenario.simulate(np.random.default_rng(3))
    with pytest.raises(PluginError, match=what):
        KinematicFitIOD(n_particles=300, range_prior=prior).estimate(ms, scenario.sensor, np.random.default_rng(11))
