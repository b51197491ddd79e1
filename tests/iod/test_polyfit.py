"""The shared-design-matrix polynomial fit (cistrack.plugins.iod.polyfit)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import IODError
from cistrack.plugins.iod.polyfit import evaluation_weights, fit_value_and_rate, truncation_bounds

TIMES = np.array([0.0, 0.031, 0.059, 0.092, 0.118, 0.151, 0.179, 0.212, 0.24, 0.27])


@pytest.mark.parametrize("degree", [0, 1, 2, 3, 4])
def test_polynomials_up_to_the_order_are_reproduced_exactly(degree):
    coef = np.arange(1.0, degree + 2.0)
    y = np.polynomial.polynomial.polyval(TIMES, coef)
    value, rate = fit_value_and_rate(TIMES, y[None, :, None], 4, TIMES[-1])
    expected_rate = np.polynomial.polynomial.polyval(TIMES[-1], np.polynomial.polynomial.polyder(coef))
    assert value[0, 0] == pytest.approx(np.polynomial.polynomial.polyval(TIMES[-1], coef), rel=1e-11)
    assert rate[0, 0] == pytest.approx(expected_rate, rel=1e-9, abs=1e-9)


def test_one_product_equals_a_separate_least_squares_fit_per_sample():
    rng = np.random.default_rng(0)
    data = rng.normal(size=(50, TIMES.size, 3))
    value, rate = fit_value_and_rate(TIMES, data, 4, TIMES[-1])
    for n in (0, 17, 49):
        for d in range(3):
            c = np.polynomial.polynomial.polyfit(TIMES, data[n, :, d], 4)
            assert value[n, d] == pytest.approx(np.polynomial.polynomial.polyval(TIMES[-1], c), abs=1e-9)
            dc = np.polynomial.polynomial.polyder(c)
            assert rate[n, d] == pytest.approx(np.polynomial.polynomial.polyval(TIMES[-1], dc), abs=1e-6)


def test_truncation_bound_holds_for_an_exponential():
    # y = exp(3 t): every derivative is known, M = 3^5 exp(3 t_max) for order 4.
    k = 3.0
    y = np.exp(k * TIMES)
    value, rate = fit_value_and_rate(TIMES, y[:, None], 4, TIMES[-1])
    b0, b1 = truncation_bounds(TIMES, 4, TIMES[-1])
    m = k ** 5 * np.exp(k * TIMES[-1])
    assert abs(value[0] - np.exp(k * TIMES[-1])) <= b0 * m
    assert abs(rate[0] - k * np.exp(k * TIMES[-1])) <= b1 * m
    assert abs(rate[0] - k * np.exp(k * TIMES[-1])) > 1e-3 * b1 * m  # and the bound is not vacuous


def test_too_few_points_for_the_order_is_an_iod_error():
    with pytest.raises(IODError, match="at least 5"):
        evaluation_weights(TIMES[:4], 4, TIMES[3])


def test_non_increasing_times_are_an_iod_error():
    with pytest.raises(IODError, match="increase"):
        evaluation_weights(TIMES[::-1], 2, TIMES[0])
