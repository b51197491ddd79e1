"""The information bound (cistrack.evaluation.information_bound) against what is known exactly:
on a linear-Gaussian problem it is the Kalman filter's covariance; its measurement Jacobian is the
analytic one; in a real run it is written beside every filter's error, the same for every filter
that starts from the same IOD, and wider when the filter declares process noise."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.evaluation.information_bound import (BOUND_KEYS, bound_predict, bound_update,
                                                   measurement_jacobian)
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

from .linear_models import BearingSensor, LinearDynamics, LinearSensor, kalman_step


def test_on_a_linear_gaussian_problem_the_bound_is_the_kalman_covariance():
    rng = np.random.default_rng(5)
    a = rng.normal(size=(6, 6))
    p0 = a @ a.T + np.eye(6)
    dyn, sensor = LinearDynamics(), LinearSensor(sigma=0.05, coords=(0, 2, 4))
    r = np.diag(np.full(3, 0.05 ** 2))
    m, p_kf, p_bound = np.zeros(6), p0.copy(), p0.copy()
    truth, t = rng.normal(size=6), 0.0
    for dt in (0.3, 0.7, 0.2, 1.1, 0.5):
        _, stm = dyn.propagate_with_stm(truth, t, [t + dt])
        truth, t = truth @ stm[-1].T, t + dt
        m, p_kf = kalman_step(m, p_kf, dt, sensor.H, r, sensor.measure(truth, t)[0])
        p_bound = bound_predict(p_bound, stm[-1])
        p_bound = bound_update(p_bound, measurement_jacobian(sensor, truth, t, sensor.names), r)
        np.testing.assert_allclose(p_bound, p_kf, rtol=1e-9, atol=1e-12)


def test_the_measurement_jacobian_is_the_analytic_one_even_across_the_azimuth_wrap():
    sensor = BearingSensor()
    for x, y in ((1.0, 0.3), (0.7, -1e-9), (-0.4, 2.0)):  # the second sits on the 0 / 2 pi seam
        state = np.array([x, y, 0.5, 0.1, 0.2, 0.3])
        rho2 = x * x + y * y
        exact = np.zeros((2, 6))
        exact[0, :2] = (-y / rho2, x / rho2)
        exact[1, 2] = 1.0
        np.testing.assert_allclose(measurement_jacobian(sensor, state, 0.0, sensor.names), exact,
                                   rtol=1e-6, atol=1e-9)


def _run(filter_table: dict, seed: int = 2):
    scen = load_scenario("quick").with_overrides({"filter": filter_table})
    return run_scenario(scen, seed=seed)


@pytest.fixture(scope="module")
def pgm_and_ukf():
    return _run({"name": "pgm", "n_particles": 500}), _run({"name": "ukf"})


def test_every_step_of_a_run_with_a_truth_carries_the_bound(pgm_and_ukf):
    rows = pgm_and_ukf[0].rows
    assert all(all(k in r and np.isfinite(r[k]) for k in BOUND_KEYS) for r in rows)
    first, last = rows[0], rows[-1]
    assert last["bound_pos_km"] < first["bound_pos_km"] / 100  # the passes' information


def test_the_bound_is_the_same_for_every_filter_starting_from_the_same_iod(pgm_and_ukf):
    pgm, ukf = ([r["bound_pos_km"] for r in res.rows] for res in pgm_and_ukf)
    np.testing.assert_allclose(pgm, ukf, rtol=1e-12)


def test_declared_process_noise_widens_the_bound(pgm_and_ukf):
    noisy = _run({"name": "pgm", "n_particles": 500, "velocity_noise_kms_per_sqrt_day": 1e-4})
    quiet = pgm_and_ukf[0]
    assert noisy.rows[-1]["bound_pos_km"] > 1.01 * quiet.rows[-1]["bound_pos_km"]


def test_a_run_without_a_truth_has_no_bound(tmp_path):
    from cistrack.plugins.readers.csv_file import write_measurements

    res = _run({"name": "ukf"})
    obs = tmp_path / "obs.csv"
    write_measurements(obs, res.context.measurements, res.context.scenario.epoch)
    scen = load_scenario("quick").with_overrides({"measurements": {"file": str(obs)}, "filter": {"name": "ukf"}})
    rows = run_scenario(scen, seed=2).rows
    assert not any(k in r for r in rows for k in BOUND_KEYS)
