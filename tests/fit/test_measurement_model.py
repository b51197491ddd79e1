"""The fit's measurement model: angle residuals wrap at ±pi, the finite-difference Jacobian is
the sensor's linear map, a sensor's own ``measurement_jacobian`` is used when it has one, and
range components are left out unless asked for."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.model.measurement import MeasurementSet

from .arcs import cr3bp_arc
from .linear_components import LinearSensor


class _AngularLinear(LinearSensor):
    angular = (True, False, False)


def test_angle_residuals_wrap_at_plus_minus_pi():
    sen = _AngularLinear()
    state = np.linalg.lstsq(sen.matrix, np.array([-np.pi + 1e-6, 0.0, 0.0]), rcond=None)[0]
    observed = np.array([[np.pi - 1e-6, 0.0, 0.0]])       # 2e-6 rad the other way round the circle
    model = MeasurementModel(sen, MeasurementSet([0.0], observed, np.full((1, 3), 1e-6), sen.names))
    np.testing.assert_allclose(model.residuals(state[None])[0], [-2e-6, 0.0, 0.0], atol=1e-9)


def test_finite_difference_jacobian_is_the_linear_sensors_matrix():
    sen = LinearSensor()
    ms = sen.simulate(np.zeros((3, 6)), np.arange(3.0), np.random.default_rng(0))
    jac = MeasurementModel(sen, ms).jacobian(np.random.default_rng(1).standard_normal((3, 6)))
    for k in range(3):
        np.testing.assert_allclose(jac[k], sen.matrix, rtol=1e-7, atol=1e-9)


class _AnalyticSensor(LinearSensor):
    calls = 0

    def measurement_jacobian(self, states, t):
        type(self).calls += 1
        return np.broadcast_to(self.matrix, (np.atleast_2d(states).shape[0], 3, 6)).copy()


def test_a_sensors_own_measurement_jacobian_is_used():
    sen = _AnalyticSensor()
    ms = sen.simulate(np.zeros((3, 6)), np.arange(3.0), np.random.default_rng(0))
    MeasurementModel(sen, ms).jacobian(np.zeros((3, 6)))
    assert _AnalyticSensor.calls == 1


def test_range_components_are_left_out_unless_asked_for():
    from cistrack.plugin.registry import default_registry

    arc = cr3bp_arc()
    sen = default_registry().create("sensor", "ground-telescope", measure_range=True)
    ms = sen.simulate(arc.truth, arc.times, np.random.default_rng(0))
    assert MeasurementModel(sen, ms).names == ("azimuth", "elevation")
    assert MeasurementModel(sen, ms, use_range=True).names == ("azimuth", "elevation", "range")
