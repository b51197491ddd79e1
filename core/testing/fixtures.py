"""Small realistic inputs for the conformance checks (all nondimensional synodic, TU).

Every fixture is built from a seed, so each check sees the same data on every run.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces.schedule import Pass
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.units import hours_to_tu, km_to_lu, kms_to_vu
from cistrack.testing.reference_dynamics import ReferenceCR3BP
from cistrack.testing.reference_sensor import GeocentricAnglesSensor

__all__ = [
    "NRHO_9_2_APOLUNE", "nrho_states", "lunar_distance_states", "nrho_truth", "first_pass",
    "initial_cloud", "two_blobs", "sample_passes", "FIXTURE_SEED",
]

FIXTURE_SEED = 20240917

NRHO_9_2_APOLUNE = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])
"""Approximate 9:2 L2 southern NRHO state at apolune (published approximate initial condition), LU and VU."""

MEASUREMENT_INTERVAL_TU = float(hours_to_tu(40.0 / 60.0))
"""Interval between simulated measurements: 40 minutes, in TU."""


def nrho_states(n: int = 5) -> np.ndarray:
    """(n, 6) states near the 9:2 NRHO: the apolune state, perturbed copies (tens of km,
    cm/s to m/s) and, as the last row, a state near perilune (fast, close to the Moon)."""
    rng = np.random.default_rng(FIXTURE_SEED)
    scale = np.concatenate([np.full(3, km_to_lu(50.0)), np.full(3, kms_to_vu(1e-3))])
    x = NRHO_9_2_APOLUNE + scale * rng.standard_normal((n, 6))
    x[0] = NRHO_9_2_APOLUNE
    if n > 1:
        x[-1] = _near_perilune()
    return x


@lru_cache(maxsize=1)
def _near_perilune() -> np.ndarray:
    prop = ReferenceCR3BP().propagate(NRHO_9_2_APOLUNE[None], 0.0, 0.70)
    return prop.final[0].copy()


def lunar_distance_states(n: int = 6) -> np.ndarray:
    """(n, 6) states one lunar distance (1 LU) from the Earth's centre in various directions,
    moving at about 1 km/s."""
    rng = np.random.default_rng(FIXTURE_SEED + 1)
    u = rng.standard_normal((n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    u[:, 2] *= 0.5  # keep elevations moderate
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = rng.standard_normal((n, 3))
    v *= kms_to_vu(1.0) / np.linalg.norm(v, axis=1, keepdims=True)
    earth = np.array([-MU_EARTH_MOON, 0.0, 0.0])
    return np.concatenate([earth + u, v], axis=1)


@lru_cache(maxsize=4)
def nrho_truth(n_times: int = 16, interval_tu: float = MEASUREMENT_INTERVAL_TU) -> tuple[np.ndarray, np.ndarray]:
    """Truth trajectory of the 9:2 NRHO from apolune: times (K,) TU and states (K, 6)."""
    times = interval_tu * np.arange(n_times)
    prop = ReferenceCR3BP().propagate(NRHO_9_2_APOLUNE[None], 0.0, times[1:])
    states = np.concatenate([NRHO_9_2_APOLUNE[None], prop.states[:, 0]], axis=0)
    return times.copy(), states


def first_pass(n_times: int = 16, range_fraction: float = 0.1, seed: int = FIXTURE_SEED) -> tuple[MeasurementSet, GeocentricAnglesSensor]:
    """A simulated first pass: ``n_times`` measurements 40 min apart of the NRHO from the
    geocentric fixture sensor (azimuth, elevation at 1.5 arcsec and an IOD-only range with
    one-sigma ``range_fraction`` x range). Returns (measurements, sensor)."""
    times, states = nrho_truth(n_times)
    sensor = GeocentricAnglesSensor(range_fraction=range_fraction)
    return sensor.simulate(states, times, np.random.default_rng(seed)), sensor


def initial_cloud(n: int = 300, seed: int = FIXTURE_SEED) -> tuple[ParticleCloud, np.ndarray]:
    """A Gaussian cloud (n, 6) around the NRHO apolune truth at t = 0 (100 km and 1 m/s per
    axis, one sigma). Returns (cloud, truth state (6,))."""
    rng = np.random.default_rng(seed)
    scale = np.concatenate([np.full(3, km_to_lu(100.0)), np.full(3, kms_to_vu(1e-3))])
    truth = NRHO_9_2_APOLUNE.copy()
    states = truth + scale * rng.standard_normal((n, 6))
    return ParticleCloud(states, 0.0), truth


def two_blobs(n_per_blob: int = 100, seed: int = FIXTURE_SEED) -> tuple[np.ndarray, np.ndarray]:
    """Two well-separated Gaussian blobs of particles near the NRHO: x (2n, 6), true labels
    (2n,). The blobs are 2,000 km apart; each has 50 km and 5 cm/s spread."""
    rng = np.random.default_rng(seed)
    scale = np.concatenate([np.full(3, km_to_lu(50.0)), np.full(3, kms_to_vu(5e-5))])
    offset = np.zeros(6)
    offset[:3] = km_to_lu(2000.0) / np.sqrt(3.0)
    a = NRHO_9_2_APOLUNE + scale * rng.standard_normal((n_per_blob, 6))
    b = NRHO_9_2_APOLUNE + offset + scale * rng.standard_normal((n_per_blob, 6))
    x = np.concatenate([a, b])
    labels = np.repeat([0, 1], n_per_blob)
    perm = rng.permutation(x.shape[0])
    return x[perm], labels[perm]


def sample_passes() -> list[Pass]:
    """Three visibility passes of 12 h, one per day, TU."""
    day = float(hours_to_tu(24.0))
    half = float(hours_to_tu(12.0))
    return [Pass(k * day, k * day + half) for k in range(3)]
