"""Conformance checks for Sensor plugins (targets a lunar distance away, 2 days of NRHO)."""
from __future__ import annotations

import numpy as np

from cistrack.errors import CistrackError
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet
from cistrack.testing.check_support import (close, describe_exception, no_global_random_state, require, round_trip, unchanged)
from cistrack.testing.fixtures import lunar_distance_states, nrho_truth

__all__ = ["SENSOR_CHECKS"]

T_CHECK = 0.1
"""TU at which single-epoch checks measure."""


def _m(sensor: Sensor) -> int:
    return len(sensor.names)


def _measure(sensor: Sensor, x: np.ndarray, t) -> np.ndarray:
    z = np.asarray(sensor.measure(x, t))
    require(z.shape == (x.shape[0], _m(sensor)),
            f"measure() returned shape {z.shape} for {x.shape[0]} states, expected (N, m) = ({x.shape[0]}, {_m(sensor)})")
    return z


def check_is_sensor(sensor) -> None:
    require(isinstance(sensor, Sensor), f"{type(sensor).__name__} does not derive from cistrack.interfaces.Sensor")
    names, angular = tuple(sensor.names), tuple(sensor.angular)
    require(len(names) >= 1 and all(isinstance(n, str) for n in names), f"names must be a non-empty tuple of str, got {names}")
    require(len(angular) == len(names) and all(isinstance(a, (bool, np.bool_)) for a in angular),
            f"angular {angular} must give one bool per component of names {names}")


def check_measure_shape_and_units(sensor) -> None:
    """measure() -> (N, m) finite floats: angles in radians, a 'range' component in LU equal
    to the distance from observer_position(); sigmas() > 0; noise_covariance() (N, m, m)."""
    x = lunar_distance_states(6)
    z = _measure(sensor, x, T_CHECK)
    require(np.issubdtype(z.dtype, np.floating) and np.all(np.isfinite(z)), "measure() returned non-float or non-finite values")
    ang = np.asarray(sensor.angular, dtype=bool)
    require(np.all(np.abs(z[:, ang]) <= 2 * np.pi + 1e-12), "angular components exceed 2π: are they in degrees instead of radians?")
    if "range" in sensor.names:
        k = list(sensor.names).index("range")
        obs = np.asarray(sensor.observer_position(T_CHECK), dtype=float)
        rho = np.linalg.norm(x[:, :3] - obs, axis=1)
        ok, diff = close(z[:, k], rho, 1e-9, 1e-12)
        require(ok, f"'range' differs from |position - observer_position(t)| by {diff:.3g} LU (range must be in LU)")
    s = np.asarray(sensor.sigmas(x, T_CHECK))
    require(s.shape == z.shape, f"sigmas() returned shape {s.shape}, expected {z.shape}")
    require(np.all(np.isfinite(s)) and np.all(s > 0), "sigmas() must be finite and > 0")
    r = np.asarray(sensor.noise_covariance(x, T_CHECK))
    m = _m(sensor)
    require(r.shape == (x.shape[0], m, m), f"noise_covariance() returned shape {r.shape}, expected (N, m, m)")
    ok, diff = close(np.diagonal(r, axis1=1, axis2=2), s**2, 1e-12, 0)
    require(ok, "the diagonal of noise_covariance() is not sigmas()**2")


def check_measure_vectorised_matches_loop(sensor) -> None:
    """One call on N states (scalar t or per-state times (N,)) equals N calls on one state."""
    x = lunar_distance_states(6)
    ts = T_CHECK + 0.01 * np.arange(x.shape[0])
    whole = _measure(sensor, x, T_CHECK)
    rows = np.concatenate([_measure(sensor, x[i:i + 1], T_CHECK) for i in range(len(x))])
    ok, diff = close(sensor.residual(whole, rows), 0.0 * whole, 0, 1e-12)
    require(ok, f"measure() on {len(x)} states differs from one state at a time by {diff:.3g}")
    whole_t = _measure(sensor, x, ts)
    rows_t = np.concatenate([_measure(sensor, x[i:i + 1], ts[i]) for i in range(len(x))])
    ok, diff = close(sensor.residual(whole_t, rows_t), 0.0 * whole_t, 0, 1e-12)
    require(ok, f"measure() with per-state times (N,) differs from one state at a time by {diff:.3g}")


def _angle_columns(sensor) -> list[int]:
    return [i for i, n in enumerate(sensor.names) if n != "range"]


def check_line_of_sight_consistent(sensor) -> None:
    """observer_position(t) + range × line_of_sight(angles, t) is the measured position, to the
    sensor's declared ``line_of_sight_tolerance_lu`` (1e-9 LU for geometric sensors)."""
    cols = _angle_columns(sensor)
    if len(cols) != 2:
        return
    x = lunar_distance_states(6)
    ts = T_CHECK + 0.01 * np.arange(x.shape[0])
    z = _measure(sensor, x, ts)
    los = np.asarray(sensor.line_of_sight(z[:, cols], ts))
    require(los.shape == (x.shape[0], 3), f"line_of_sight() returned shape {los.shape}, expected (N, 3)")
    ok, diff = close(np.linalg.norm(los, axis=1), np.ones(len(x)), 0, 1e-12)
    require(ok, f"line_of_sight() vectors are not unit length (off by {diff:.3g})")
    obs = np.asarray(sensor.observer_position(ts), dtype=float)
    require(obs.shape == (len(ts), 3), f"observer_position() of (K,) times returned shape {obs.shape}, expected (K, 3)")
    rho = np.linalg.norm(x[:, :3] - obs, axis=1)
    tol = float(getattr(sensor, "line_of_sight_tolerance_lu", 1e-9))
    ok, diff = close(obs + rho[:, None] * los, x[:, :3], 0, tol)
    require(ok, f"observer + range × line_of_sight misses the true position by {diff:.3g} LU "
                f"(the sensor declares line_of_sight_tolerance_lu = {tol:.3g})")


def check_observer_and_visibility_shapes(sensor) -> None:
    o = np.asarray(sensor.observer_position(T_CHECK))
    require(o.shape == (3,) and np.all(np.isfinite(o)), f"observer_position(scalar) returned shape {o.shape}, expected (3,)")
    require(np.linalg.norm(o) < 10.0, f"observer at {o} LU is beyond cislunar space: is it in km instead of LU?")
    x = lunar_distance_states(6)
    v = np.asarray(sensor.visible(x, T_CHECK))
    require(v.shape == (len(x),) and v.dtype == bool, f"visible() returned {v.dtype} shape {v.shape}, expected (N,) bool")


def check_observer_path_consistent(sensor) -> None:
    """observer_position() at a time is the same whatever was asked before (two fresh copies
    asked the same times in opposite orders agree exactly: a sensor that moves, e.g. on its own
    orbit, must not depend on its history), and one call on (K,) times equals K scalar calls
    to 1e-9 LU; every position is finite and in LU."""
    ts = T_CHECK + np.array([0.9, 0.0, 0.45, 8.0, 0.2])   # 8 TU: past 32 days
    order = np.argsort(ts)
    up, down = round_trip(sensor), round_trip(sensor)
    rising = {float(ts[i]): np.asarray(up.observer_position(float(ts[i])), dtype=float) for i in order}
    falling = {float(ts[i]): np.asarray(down.observer_position(float(ts[i])), dtype=float) for i in order[::-1]}
    diff = max(float(np.max(np.abs(rising[t] - falling[t]))) for t in rising)
    require(diff == 0.0, f"observer_position() depends on the times asked before (off by {diff:.3g} LU)")
    whole = np.asarray(sensor.observer_position(ts[order]), dtype=float)
    require(whole.shape == (len(ts), 3) and np.all(np.isfinite(whole)),
            f"observer_position() of (K,) times returned shape {whole.shape} or non-finite values")
    require(np.all(np.linalg.norm(whole, axis=1) < 10.0), "the observer leaves cislunar space: km instead of LU?")
    ok, diff = close(np.stack([rising[float(t)] for t in ts[order]]), whole, 0, 1e-9)
    require(ok, f"observer_position() of (K,) times differs from K scalar calls by {diff:.3g} LU")


def check_residual_wraps_angles(sensor) -> None:
    ang = np.asarray(sensor.angular, dtype=bool)
    if not ang.any():
        return
    z = _measure(sensor, lunar_distance_states(6), T_CHECK)
    z2 = z.copy()
    z2[:, ang] += 2.0 * np.pi
    r = np.asarray(sensor.residual(z2, z))
    ok, diff = close(r, 0.0 * r, 0, 1e-9)
    require(ok, f"residual() of angles 2π apart is {diff:.3g}, not 0: wrap angular components into [-π, π)")


def _simulate(sensor, seed: int) -> tuple[MeasurementSet, np.ndarray, np.ndarray]:
    times, states = nrho_truth(72)
    ms = sensor.simulate(states, times, np.random.default_rng(seed))
    require(isinstance(ms, MeasurementSet), f"simulate() returned {type(ms).__name__}, not MeasurementSet")
    return ms, times, states


def check_simulate_noise_matches_sigmas(sensor) -> None:
    """Simulated measurements of 2 days of NRHO truth: names match, times are a subset of the
    truth's, and residuals divided by sigmas have unit spread (noise in the right units)."""
    ms, times, states = _simulate(sensor, 1)
    require(tuple(ms.names) == tuple(sensor.names), f"simulate() names {ms.names} differ from sensor.names {sensor.names}")
    vis = np.asarray(sensor.visible(states, times))
    if vis.any():
        require(len(ms) > 0, "simulate() returned no measurement although visible() is True at some times")
    if len(ms) == 0:
        return
    idx = np.searchsorted(times, ms.times)
    idx = np.clip(idx, 0, len(times) - 1)
    require(np.allclose(times[idx], ms.times, rtol=0, atol=1e-12), "simulate() returned times that are not truth times")
    zhat = _measure(sensor, states[idx], ms.times)
    u = np.asarray(sensor.residual(ms.values, zhat)) / ms.sigmas
    rms = float(np.sqrt(np.mean(u * u)))
    require(0.6 < rms < 1.5, f"simulated noise / sigmas has RMS {rms:.3g}, expected about 1: are noise and sigmas "
                             "in the same units (radians, LU)?")


def check_simulate_reproducible(sensor) -> None:
    with no_global_random_state("simulate()"):
        a, _, _ = _simulate(sensor, 7)
    b, _, _ = _simulate(sensor, 7)
    c, _, _ = _simulate(sensor, 8)
    require(np.array_equal(a.values, b.values) and np.array_equal(a.times, b.times),
            "simulate() with generators of the same seed gave different measurements")
    if len(a):
        require(not np.array_equal(a.values, c.values), "simulate() gave the same noise for different seeds")


def check_inputs_not_mutated(sensor) -> None:
    x = lunar_distance_states(4)
    times, states = nrho_truth(72)
    times, states = times.copy(), states.copy()
    with unchanged(states=x, truth=states, times=times):
        sensor.measure(x, T_CHECK)
        sensor.sigmas(x, T_CHECK)
        sensor.visible(x, T_CHECK)
        sensor.simulate(states, times, np.random.default_rng(0))


def check_same_after_pickle(sensor) -> None:
    x = lunar_distance_states(4)
    other = round_trip(sensor)
    ok, diff = close(sensor.measure(x, T_CHECK), other.measure(x, T_CHECK), 0, 0)
    require(ok, f"the unpickled copy measures differently (by {diff:.3g})")


def check_rejects_malformed_states(sensor) -> None:
    try:
        sensor.measure(np.zeros((3, 5)), T_CHECK)
    except CistrackError:
        return
    except Exception as exc:
        require(False, f"measure() with states of shape (3, 5) raised {describe_exception(exc)}; raise a "
                       "cistrack.errors error that says what is wrong")
    require(False, "measure() accepted states of shape (3, 5)")


SENSOR_CHECKS = [
    ("is_sensor", check_is_sensor),
    ("measure_shape_and_units", check_measure_shape_and_units),
    ("measure_vectorised_matches_loop", check_measure_vectorised_matches_loop),
    ("line_of_sight_consistent", check_line_of_sight_consistent),
    ("observer_and_visibility_shapes", check_observer_and_visibility_shapes),
    ("observer_path_consistent", check_observer_path_consistent),
    ("residual_wraps_angles", check_residual_wraps_angles),
    ("simulate_noise_matches_sigmas", check_simulate_noise_matches_sigmas),
    ("simulate_reproducible", check_simulate_reproducible),
    ("inputs_not_mutated", check_inputs_not_mutated),
    ("same_after_pickle", check_same_after_pickle),
    ("rejects_malformed_states", check_rejects_malformed_states),
]
