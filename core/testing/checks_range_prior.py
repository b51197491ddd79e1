"""Conformance checks for range priors (kind "range-prior")."""
from __future__ import annotations

import numpy as np

from cistrack.units import km_to_lu
from cistrack.testing.check_support import require

__all__ = ["RANGE_PRIOR_CHECKS"]


def _measured(k: int) -> np.ndarray:
    return np.full(k, float(km_to_lu(380_000.0)))


def check_draws_positive_finite_ranges_of_the_asked_shape(prior) -> None:
    for shape in ((500, 7), (500, 1)):
        rho = np.asarray(prior.draw(_measured(7), shape, np.random.default_rng(0)), dtype=float)
        try:
            np.broadcast_shapes(rho.shape, (shape[0], 7))
            ok = rho.shape[0] == shape[0]
        except ValueError:
            ok = False
        require(ok, f"draw(shape={shape}) returned shape {rho.shape}, which does not broadcast to ({shape[0]}, 7)")
        require(np.all(np.isfinite(rho)), "draw returned NaN or inf")
        require(np.mean(rho > 0) > 0.99, "more than 1% of the drawn ranges are not positive")


def check_draws_are_reproducible_from_the_generator(prior) -> None:
    a = prior.draw(_measured(3), (50, 3), np.random.default_rng(5))
    b = prior.draw(_measured(3), (50, 3), np.random.default_rng(5))
    require(np.array_equal(a, b), "the same seed gave different ranges (randomness not from rng?)")


RANGE_PRIOR_CHECKS = [
    ("draws_positive_finite_ranges_of_the_asked_shape", check_draws_positive_finite_ranges_of_the_asked_shape),
    ("draws_are_reproducible_from_the_generator", check_draws_are_reproducible_from_the_generator),
]
