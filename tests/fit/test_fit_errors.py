"""Malformed input and impossible fits are refused with errors naming what is wrong; an arc that
leaves a direction unobservable gives a warning naming it."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from cistrack.errors import MeasurementError, ParameterError, StateError
from cistrack.least_squares import FitError, FitOptions, UnobservableWarning, fit_orbit
from cistrack.model.measurement import MeasurementSet

from .arcs import GUESS_OFFSET, cr3bp_arc
from .linear_components import FreeParticle, LinearSensor


def test_fewer_components_than_unknowns_is_refused():
    arc = cr3bp_arc()
    with pytest.raises(FitError, match="4 numbers for 6 unknowns"):
        fit_orbit(arc.dynamics, arc.sensor, arc.exact.subset(np.arange(2)), arc.truth0, 0.0)


def test_a_state_of_the_wrong_shape_is_refused():
    arc = cr3bp_arc()
    with pytest.raises(StateError, match=r"shape \(6,\)"):
        fit_orbit(arc.dynamics, arc.sensor, arc.exact, arc.truth0[:5], 0.0)


def test_a_state_with_nan_is_refused():
    arc = cr3bp_arc()
    bad = arc.truth0.copy()
    bad[2] = np.nan
    with pytest.raises(StateError, match="NaN"):
        fit_orbit(arc.dynamics, arc.sensor, arc.exact, bad, 0.0)


def test_a_prior_covariance_that_is_not_positive_definite_is_refused():
    arc = cr3bp_arc()
    with pytest.raises(StateError, match="positive definite"):
        fit_orbit(arc.dynamics, arc.sensor, arc.exact, arc.truth0, 0.0, prior=(arc.truth0, -np.eye(6)))


def test_measurements_of_another_sensor_are_refused_naming_the_components():
    arc = cr3bp_arc()
    ms = MeasurementSet(arc.times, arc.exact.values, arc.exact.sigmas, ("right_ascension", "declination"))
    with pytest.raises(MeasurementError, match="right_ascension"):
        fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0, 0.0)


def test_an_initial_state_inside_the_moon_is_refused_naming_the_moon():
    arc = cr3bp_arc()
    inside = np.array([1.0 - arc.dynamics.mu, 0.0, 0.001, 0.0, 0.0, 0.0])
    with pytest.raises(FitError, match="Moon"):
        fit_orbit(arc.dynamics, arc.sensor, arc.exact, inside, 0.0)


def test_invalid_options_are_refused_naming_the_option():
    with pytest.raises(ParameterError, match="max_iterations"):
        FitOptions(max_iterations=0)


def _degenerate_sensor(scale: float) -> LinearSensor:
    sen = LinearSensor()
    sen.matrix[:, 5] = scale * sen.matrix[:, 2]     # z and vz enter only in one combination
    sen.matrix[:, 2] = 0.0
    return sen


def test_a_nearly_unobservable_direction_warns_and_is_reported_in_km():
    times = np.linspace(-1.0, 1.0, 5)
    sen = _degenerate_sensor(1.0)
    sen.matrix[0, 2] = 1e-6                          # barely separates z from vz
    ms = sen.simulate(np.zeros((5, 6)), times, np.random.default_rng(1))
    ms = MeasurementSet(times, ms.values, ms.sigmas, ms.names)
    with pytest.warns(UnobservableWarning, match="unobservable"):
        res = fit_orbit(FreeParticle(), sen, ms, np.zeros(6), 0.0)
    assert res.unobservable and res.condition_number > 1e7
    w = res.weakest_direction_km
    assert abs(w[2]) > 10 * np.max(np.abs(np.delete(w, [2, 5])))   # the z/vz direction


def _correlated_but_precise_arc() -> tuple[LinearSensor, MeasurementSet]:
    """z and vz separated only weakly (condition number 3.9e8) but measured so precisely that the
    weakest direction is known to 0.05 km: the geometry of a dense arc, not a short one."""
    times = np.linspace(-1.0, 1.0, 5)
    sen = _degenerate_sensor(1.0)
    sen.matrix[0, 2] = 1e-4
    sen.sigma = 1e-14
    ms = sen.simulate(np.zeros((5, 6)), times, np.random.default_rng(1))
    return sen, MeasurementSet(times, ms.values, ms.sigmas, ms.names)


def test_a_high_condition_number_with_the_weakest_direction_known_to_metres_is_not_flagged():
    sen, ms = _correlated_but_precise_arc()
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnobservableWarning)
        res = fit_orbit(FreeParticle(), sen, ms, np.zeros(6), 0.0)
    assert res.condition_number > 1e7 > 0
    assert np.linalg.norm(res.weakest_direction_km[:3]) < 0.1
    assert not res.unobservable


def test_min_weak_sigma_zero_lets_the_condition_number_flag_alone():
    sen, ms = _correlated_but_precise_arc()
    with pytest.warns(UnobservableWarning, match="condition number"):
        res = fit_orbit(FreeParticle(), sen, ms, np.zeros(6), 0.0, options=FitOptions(min_weak_sigma_km=0.0))
    assert res.unobservable


def test_a_negative_min_weak_sigma_is_refused_naming_the_option():
    with pytest.raises(ParameterError, match="min_weak_sigma_km.*>= 0"):
        FitOptions(min_weak_sigma_km=-1.0)


def test_an_unobservable_direction_with_no_information_is_refused():
    times = np.linspace(-1.0, 1.0, 5)
    sen = _degenerate_sensor(0.0)                    # nothing depends on z or vz at all
    ms = sen.simulate(np.zeros((5, 6)), times, np.random.default_rng(1))
    with pytest.raises(FitError, match="not positive definite"):
        fit_orbit(FreeParticle(), sen, ms, np.zeros(6), 0.0)


def test_a_singular_normal_matrix_is_called_singular_in_words_not_an_infinite_condition_number():
    """The refusal had read "not positive definite (condition number inf)"."""
    times = np.linspace(-1.0, 1.0, 5)
    sen = _degenerate_sensor(0.0)
    ms = sen.simulate(np.zeros((5, 6)), times, np.random.default_rng(1))
    with pytest.raises(FitError, match=r"not positive definite \(singular \(no finite condition number\)\)") as err:
        fit_orbit(FreeParticle(), sen, ms, np.zeros(6), 0.0)
    assert "inf" not in str(err.value).replace("information", "")


def test_a_fit_settling_far_above_the_noise_is_reported_as_not_converged():
    arc = cr3bp_arc()
    ms = arc.noisy(1)
    stated = MeasurementSet(ms.times, ms.values, ms.sigmas / 1000.0, ms.names)   # noise 1000x understated
    res = fit_orbit(arc.dynamics, arc.sensor, stated, arc.truth0 + GUESS_OFFSET, 0.0,
                    options=FitOptions(reject_outliers=False))
    assert not res.converged and res.rms > 100.0
    assert any("does not fit the observations" in m for m in res.messages)


@pytest.mark.slow
def test_an_iod_that_finds_no_orbit_says_what_it_tried_in_words(tmp_path, capsys):
    from cistrack.cli.main import main
    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    assert main(["fit", str(obs), "--out", str(tmp_path / "f"), "--quiet", "--set",
                 "measurements.reader.sites={809={latitude_deg=0,longitude_deg=0,height_m=0}}"]) == 3
    err = capsys.readouterr().err
    assert "8 tried: tracklet 1 scored on 2, 3, 4:" in err and "{'seed'" not in err
