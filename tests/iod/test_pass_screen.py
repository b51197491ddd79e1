"""The first pass's gross outliers are left out of the IOD's fit; data that only scatter lose
nothing (plugins/iod/pass_screen.py)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.iod.pass_screen import screen_pass
from cistrack.units import ARCSEC_RAD

HOUR_TU = 3600.0 / 375_190.0


def _pass(n=12, hours=6.0, sigma_arcsec=1.5, seed=0):
    """Lines of sight (n, 3) from a point on the rotating Earth to a target at lunar distance
    moving 1 km/s, over ``hours``, with isotropic angular noise; times (n,) TU; sigma (n,) rad."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, hours * HOUR_TU, n)
    w_earth = 2 * np.pi / (24 * HOUR_TU)
    target = np.stack([384_400.0 * np.cos(0.23 * t), 384_400.0 * np.sin(0.23 * t), 30_000.0 + 0 * t], axis=1)
    observer = 6378.0 * np.stack([0.8 * np.cos(w_earth * t), 0.8 * np.sin(w_earth * t), 0.6 + 0 * t], axis=1)
    u = target - observer
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    sig = np.full(n, sigma_arcsec * ARCSEC_RAD)
    u = u + rng.normal(size=u.shape) * sig[:, None] / np.sqrt(2)
    return t, u / np.linalg.norm(u, axis=1, keepdims=True), sig


def _displaced(u, i, arcsec, seed=1):
    rng = np.random.default_rng(seed)
    d = np.cross(u[i], rng.normal(size=3))
    out = u.copy()
    out[i] = u[i] + arcsec * ARCSEC_RAD * d / np.linalg.norm(d)
    out[i] /= np.linalg.norm(out[i])
    return out


@pytest.mark.parametrize("seed", range(20))
def test_a_clean_pass_loses_nothing(seed):
    t, u, sig = _pass(seed=seed)
    assert screen_pass(t, u, sig, order=4, need=8) == []


@pytest.mark.parametrize("seed", range(5))
def test_a_long_pass_the_polynomial_follows_only_roughly_loses_nothing(seed):
    t, u, sig = _pass(n=16, hours=12.0, sigma_arcsec=0.05, seed=seed)
    assert screen_pass(t, u, sig, order=4, need=8) == []


@pytest.mark.parametrize("where", [0, 5, 11])
def test_one_observation_a_degree_off_is_left_out_wherever_it_lies(where):
    t, u, sig = _pass(seed=3)
    found = screen_pass(t, _displaced(u, where, 3600.0), sig, order=4, need=8)
    assert [i for i, _ in found] == [where]
    assert found[0][1] / ARCSEC_RAD == pytest.approx(3600.0, rel=0.01)


def test_two_gross_outliers_are_both_left_out():
    t, u, sig = _pass(n=14, seed=4)
    bad = _displaced(_displaced(u, 2, 2000.0), 9, 5000.0, seed=2)
    assert sorted(i for i, _ in screen_pass(t, bad, sig, order=4, need=8)) == [2, 9]


def test_an_outlier_of_tens_of_sigma_is_left_to_the_filter_and_the_least_squares():
    t, u, sig = _pass(seed=5)
    assert screen_pass(t, _displaced(u, 6, 60.0), sig, order=4, need=8) == []


def test_the_pass_never_gets_shorter_than_the_fit_needs():
    t, u, sig = _pass(n=8, seed=6)
    assert screen_pass(t, _displaced(u, 3, 3600.0), sig, order=4, need=8) == []
