"""A Gaussian mixture whose density is evaluated twice (a run's metrics evaluate each belief at its
samples and then at the truth) inverts its Cholesky factors once, and gives the same numbers as a
mixture evaluated for the first time (issue 51)."""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import GaussianMixture


def _mixture() -> GaussianMixture:
    rng = np.random.default_rng(7)
    a = rng.normal(size=(3, 6, 6))
    covariances = a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(6)
    return GaussianMixture(np.array([0.5, 0.3, 0.2]), rng.normal(size=(3, 6)), covariances)


def test_a_second_density_evaluation_does_not_invert_the_cholesky_factors_again(monkeypatch):
    mix = _mixture()
    inverted = []
    real_inv = np.linalg.inv

    def counting_inv(a):
        inverted.append(np.shape(a))
        return real_inv(a)

    monkeypatch.setattr(np.linalg, "inv", counting_inv)
    mix.logpdf(np.zeros((50, 6)))
    mix.logpdf(np.ones((1, 6)))
    assert inverted == [(3, 6, 6)]


def test_the_second_evaluation_gives_the_densities_of_a_fresh_mixture_bit_for_bit():
    points = np.random.default_rng(8).normal(size=(200, 6))
    used = _mixture()
    used.logpdf(np.zeros((10, 6)))
    assert np.array_equal(used.logpdf(points), _mixture().logpdf(points))
    assert np.array_equal(used.component_logpdf(points), _mixture().component_logpdf(points))
