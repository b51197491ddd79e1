"""The least squares' partials of the measurements with respect to an impulsive burn's delta-v,
taken from the state transition matrices (:mod:`cistrack.least_squares.impulse_partials`), against
an independent central difference of step 1e-4 m/s through models built with the burn moved:
burns after and before the fit epoch, a burn at zero delta-v (where a fit starts), two burns at
once, and a burn beside the area-to-mass ratio (which keeps its central difference)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.interfaces.maneuvers import Impulse
from cistrack.least_squares.differential_correction import _Problem
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.solve_for_parameters import SolveFor
from cistrack.least_squares.trajectory import arc_states
from cistrack.propagation.impulses import MS_PER_VU, ImpulsiveDynamics, delta_v_parameter_names

from .test_area_to_mass_recovery import simulate

H_MS = 1e-4


def _burns(dyn, times_days, dvs_ms):
    from cistrack.units import days_to_tu
    return ImpulsiveDynamics(dyn, [Impulse(float(days_to_tu(t)), np.asarray(dv, float) / MS_PER_VU, f"b{k}")
                                   for k, (t, dv) in enumerate(zip(times_days, dvs_ms))])


def _independent(model, flown, x0, t0, k, axis):
    """Central difference of the predicted measurements (K, m) for burn k's axis, rad per m/s."""
    z = []
    for s in (1.0, -1.0):
        imps = list(flown.impulses)
        dv = imps[k].dv.copy()
        dv[axis] += s * H_MS / MS_PER_VU
        imps[k] = Impulse(imps[k].t, dv, imps[k].label)
        z.append(model.predict(arc_states(ImpulsiveDynamics(flown.base, imps), x0, t0, model.times)))
    return (z[0] - z[1]) / (2.0 * H_MS)


def _columns(flown, model, x, t0, names):
    prob = _Problem(flown, model, t0, None, SolveFor(flown, names))
    return prob.jacobian(x)[:, :, 6:] * model.sigmas[:, :, None]


@pytest.mark.parametrize("t0_days, dv_ms", [(0.0, [0.3, -0.2, 0.1]), (6.0, [0.3, -0.2, 0.1]), (0.0, [0.0, 0.0, 0.0]),
                                            (6.0, [0.0, 0.0, 0.0])])
def test_one_burns_partials_agree_with_an_independent_central_difference(t0_days, dv_ms):
    from cistrack.units import days_to_tu
    dyn, sensor, ms, x0 = simulate(0.0, 6.0, seed=7)
    model = MeasurementModel(sensor, ms)
    flown = _burns(dyn, [3.1], [dv_ms])
    t0 = float(days_to_tu(t0_days))
    x = arc_states(flown, x0, 0.0, np.array([t0]))[0]
    cols = _columns(flown, model, np.concatenate([x, dv_ms]), t0, delta_v_parameter_names(0))
    for axis in range(3):
        want = _independent(model, flown, x, t0, 0, axis)
        assert np.abs(want).max() > 1e-6                       # rad per m/s: the burn moves what is seen
        np.testing.assert_allclose(cols[:, :, axis], want, rtol=1e-5, atol=1e-6 * np.abs(want).max())


def test_two_burns_either_side_of_the_epoch_and_the_area_to_mass_ratio_together():
    from cistrack.units import days_to_tu
    dyn, sensor, ms, x0 = simulate(0.0, 6.0, seed=7)
    model = MeasurementModel(sensor, ms)
    flown = _burns(dyn, [1.6, 4.2], [[0.2, 0.0, -0.1], [0.0, 0.5, 0.0]])
    t0 = float(days_to_tu(3.0))
    x = arc_states(flown, x0, 0.0, np.array([t0]))[0]
    names = ("area_to_mass_m2_kg",) + delta_v_parameter_names(0) + delta_v_parameter_names(1)
    values = np.array([0.0, 0.2, 0.0, -0.1, 0.0, 0.5, 0.0])
    cols = _columns(flown, model, np.concatenate([x, values]), t0, names)
    for j, (k, axis) in enumerate([(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)], start=1):
        want = _independent(model, flown, x, t0, k, axis)
        np.testing.assert_allclose(cols[:, :, j], want, rtol=1e-5, atol=1e-6 * np.abs(want).max())
    before, after = model.times <= flown.impulses[0].t, model.times > flown.impulses[1].t
    assert np.all(cols[~before, :, 1:4] == 0.0) and np.all(cols[~after, :, 4:7] == 0.0)   # each burn moves its side only
    assert np.abs(cols[:, :, 0]).max() > 0.0                                                # the ratio's column is there
