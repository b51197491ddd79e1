"""The sigma of a burn's size |dv| (BurnEstimate.magnitude_sigma_ms), against a Monte Carlo of
its Gaussian delta-v."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.least_squares.impulse_fit import BurnEstimate

WIDE_ACROSS = 1e-4 * np.array([[128.918, 30.8435, -9.0716],   # (m/s)^2: an unseen campaign's burn, 0.11 m/s
                               [30.8435, 7.5897, -2.1441],     # across its delta-v, 0.005 along it
                               [-9.0716, -2.1441, 0.7687]])


def _monte_carlo_sigma(dv: np.ndarray, cov: np.ndarray) -> float:
    draws = np.random.default_rng(20261130).multivariate_normal(dv, cov, 400_000)
    return float(np.linalg.norm(draws, axis=1).std())


def test_a_size_uncertain_across_its_direction_has_the_sigma_of_its_monte_carlo():
    dv = np.array([0.170, -0.713, -0.251])
    burn = BurnEstimate(1.0, dv, WIDE_ACROSS)
    linear = float(np.sqrt(dv @ WIDE_ACROSS @ dv)) / np.linalg.norm(dv)
    assert burn.magnitude_sigma_ms > 1.5 * linear  # the curvature of |dv| matters here
    assert burn.magnitude_sigma_ms == pytest.approx(_monte_carlo_sigma(dv, WIDE_ACROSS), rel=0.05)


def test_a_size_well_determined_in_every_direction_keeps_its_linear_sigma():
    dv = np.array([0.3, -0.4, 0.1])
    cov = np.diag([1e-6, 4e-6, 2e-6])
    u = dv / np.linalg.norm(dv)
    assert BurnEstimate(1.0, dv, cov).magnitude_sigma_ms == pytest.approx(np.sqrt(u @ cov @ u), rel=1e-4)


def test_an_isotropic_uncertainty_adds_sigma_to_the_fourth_over_the_size_squared():
    """u^T C u = s^2 and tr((P C P)^2) = 2 s^4 for C = s^2 I: sigma^2 = s^2 + s^4 / |dv|^2."""
    s, dv = 0.2, np.array([0.0, 0.5, 0.0])
    assert BurnEstimate(1.0, dv, s * s * np.eye(3)).magnitude_sigma_ms == pytest.approx(np.sqrt(s**2 + s**4 / 0.25))
