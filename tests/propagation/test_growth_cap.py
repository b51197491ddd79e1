"""The step-size controller's factor: err^-1/8 from three square roots and a division (IEEE
754, the same on every machine), close to ``pow``'s; and its shortcut: below a bound on the error
estimate an accepted step grows by MAX_GROWTH without evaluating the factor, giving what
``min(MAX_GROWTH, ...)`` gives."""
from __future__ import annotations

import math

import numpy as np

from cistrack.propagation.dop853_source import generate_source, growth_cap_error, step_factor_source

SAFETY, MAX_GROWTH = 0.8, 4.0


def _factor(err: float) -> float:
    """The generated kernels' accepted-step factor with I control, as they compute it."""
    return min(MAX_GROWTH, SAFETY / math.sqrt(math.sqrt(math.sqrt(err))))


def test_errors_at_or_below_the_bound_give_the_capped_factor_exactly():
    cap = growth_cap_error(SAFETY, MAX_GROWTH, 0.0)
    rng = np.random.default_rng(7)
    errs = np.concatenate([[cap, np.nextafter(cap, 0.0), 1e-300, 5e-324],
                           cap * (1.0 - np.logspace(-15, -1, 500)), cap * rng.uniform(0.0, 1.0, 2000)])
    assert all(_factor(float(e)) == MAX_GROWTH for e in errs)


def test_the_bound_sits_just_below_where_the_factor_leaves_the_cap():
    cap = growth_cap_error(SAFETY, MAX_GROWTH, 0.0)
    crossover = (SAFETY / MAX_GROWTH) ** 8  # exact in real arithmetic: 2.56e-6
    assert crossover * (1 - 1e-7) < cap < crossover
    assert _factor(crossover * (1 + 1e-6)) < MAX_GROWTH


def test_pi_control_never_takes_the_shortcut():
    assert growth_cap_error(SAFETY, MAX_GROWTH, 0.04) == -1.0


def test_generated_kernels_carry_the_bound():
    src = generate_source("", 6, cache=False)
    assert f"GROWTH_CAP_ERR = {growth_cap_error(SAFETY, MAX_GROWTH, 0.0)!r}" in src
    assert src.count("<= GROWTH_CAP_ERR") == 2  # one-particle and dense-output kernels


def test_the_i_control_factor_is_three_square_roots_within_two_ulps_of_pow():
    errs = np.concatenate([np.logspace(-12, 0, 2001), np.random.default_rng(11).uniform(1e-6, 1.0, 2000)])
    roots = np.array([1.0 / math.sqrt(math.sqrt(math.sqrt(e))) for e in errs])
    powers = errs ** -0.125
    assert np.all(np.abs(roots - powers) <= 2 * np.spacing(powers))
    assert "np.sqrt(np.sqrt(np.sqrt(err)))" in step_factor_source(0.0)


def test_pi_control_keeps_pow_with_the_previous_error():
    assert "err ** -EXPO1 * err_old ** BETA" in step_factor_source(0.04)
