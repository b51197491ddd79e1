"""The least squares' partial of the measurements with respect to the area-to-mass ratio (a
central difference of step 1e-3 m^2/kg through ``with_parameters``) against an independent
central difference of step 1e-4 m^2/kg with models built by the constructor; the 7x7
covariance's blocks, sigmas and correlations, and how fit.json and the summary report them; and a clear error for dynamics without the
parameter."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import StateError
from cistrack.fitting.fit_record import area_to_mass_record, area_to_mass_summary
from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.differential_correction import _Problem
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.solve_for_parameters import SolveFor
from cistrack.least_squares.trajectory import arc_states
from cistrack.plugin.registry import default_registry

from .test_area_to_mass_recovery import EPOCH, OFFSET, simulate


def test_the_partial_agrees_with_an_independent_central_difference():
    dyn, sensor, ms, x0 = simulate(0.01, 10.0, seed=7)
    model = MeasurementModel(sensor, ms)
    p0 = 0.006
    prob = _Problem(dyn, model, 0.0, None, SolveFor(dyn, ("area_to_mass_m2_kg",)))
    col = prob.jacobian(np.concatenate([x0, [p0]]))[:, :, 6] * model.sigmas   # d z / d p, rad per m^2/kg
    reg = default_registry()
    h = 1e-4
    z = [model.predict(arc_states(reg.create("dynamics", "ephemeris", epoch=EPOCH, area_to_mass_m2_kg=p0 + s * h),
                                  x0, 0.0, model.times)) for s in (1.0, -1.0)]
    want = (z[0] - z[1]) / (2.0 * h)
    assert np.abs(want).max() > 1e-3               # rad per m^2/kg: ~0.2 arcsec for 1e-3 m^2/kg
    np.testing.assert_allclose(col, want, rtol=1e-4, atol=1e-6 * np.abs(want).max())


def test_the_seven_by_seven_covariance_is_reported_in_blocks():
    dyn, sensor, ms, x0 = simulate(0.01, 10.0, seed=7)
    res = fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass="solve"))
    assert res.full_covariance.shape == (7, 7) and res.parameters.shape == (1,)
    np.testing.assert_array_equal(res.covariance, res.full_covariance[:6, :6])
    value, sigma = res.parameter("area_to_mass_m2_kg")
    assert sigma == pytest.approx(np.sqrt(res.full_covariance[6, 6]))
    corr = res.parameter_correlations
    assert corr.shape == (1, 6) and np.all(np.abs(corr) <= 1.0)
    c = res.full_covariance
    assert corr[0, 4] == pytest.approx(c[6, 4] / np.sqrt(c[6, 6] * c[4, 4]))
    assert np.all(np.linalg.eigvalsh(c / np.sqrt(np.outer(np.diag(c), np.diag(c)))) > 0)
    rec = area_to_mass_record(res)
    assert rec["estimated"] and rec["value_m2_kg"] == value and rec["sigma_m2_kg"] == sigma
    assert rec["correlations_with_state"] == [float(v) for v in corr[0]]
    lines = area_to_mass_summary(res)
    assert len(lines) == 2 and "m^2/kg" in lines[0] and "correlations" in lines[1]
    assert area_to_mass_record(fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0)) is None


def test_dynamics_without_the_parameter_are_refused_by_name():
    reg = default_registry()
    cr3bp = reg.create("dynamics", "cr3bp")
    _, sensor, ms, x0 = simulate(0.0, 3.0, seed=7)
    with pytest.raises(StateError, match="area_to_mass_m2_kg.*ephemeris"):
        fit_orbit(cr3bp, sensor, ms, x0, 0.0, options=FitOptions(area_to_mass="solve"))


def test_an_iterate_outside_the_models_range_is_the_fits_failure_not_a_settings_error():
    """A least-squares step to C_R A/m = -1.2e11 m^2/kg (a diverging fit of a survey set) had ended
    the command as if the user had set a bad value (exit 2, no fit.json)."""
    from cistrack.least_squares.errors import FitError

    dyn = default_registry().create("dynamics", "ephemeris", epoch=EPOCH)
    with pytest.raises(FitError, match=r"area-to-mass ratio \(C_R A/m\) ran to -1\.171e\+11 m\^2/kg"):
        SolveFor(dyn, ("area_to_mass_m2_kg",)).dynamics(np.array([-117123731138.67]))


def test_its_failure_is_worded_for_a_user_not_in_the_dynamics_internal_words():
    """Probe M12: "... (area_to_mass_m2_kg = 1251): dynamics 'ephemeris': parameter 'area_to_mass_m2_kg'
    = 1251.4581033349136 is invalid: must be ..." had reached a fit's failure text."""
    from cistrack.least_squares.errors import FitError

    dyn = default_registry().create("dynamics", "ephemeris", epoch=EPOCH)
    with pytest.raises(FitError) as caught:
        SolveFor(dyn, ("area_to_mass_m2_kg",)).dynamics(np.array([1251.4581033349136]))
    assert str(caught.value) == ("the fitted area-to-mass ratio (C_R A/m) ran to 1251 m^2/kg, outside what the model "
                                 "allows (a finite number in [-1000, 1000]): these observations do not determine it")
