"""cistrack.numerics.special_functions: the incomplete gamma functions, the chi-square tails and
quantiles and log-sum-exp a run evaluates without importing scipy.special. Checked against closed
forms (chi-square with 1 and 2 degrees of freedom), exact sums in 60-digit decimal arithmetic
(even degrees of freedom), and scipy.special."""
from __future__ import annotations

import math
from decimal import Decimal, localcontext
from statistics import NormalDist

import numpy as np
import pytest
from scipy import special

from cistrack.numerics.special_functions import (chi2_cdf, chi2_isf, chi2_ppf, chi2_sf, gamma_p, gamma_q,
                                                  logsumexp)

PROBABILITIES = [1e-300, 1e-100, 1e-20, 1e-9, 1e-6, 1e-3, 0.0027, 0.025, 0.1, 0.3, 0.5, 0.7, 0.9, 0.975,
                 0.999, 0.999999]
DOFS = [1, 2, 3, 4, 5, 6, 7, 12, 22, 29, 58, 99.5, 150, 300, 2000]


def _upper_tail_exact(k: int, x: float) -> float:
    """Q(k, x) for a whole k: e^-x times the sum of x^j / j! for j < k, in 60 digits."""
    with localcontext() as ctx:
        ctx.prec = 60
        xd, term, total = Decimal(x), Decimal(1), Decimal(0)
        for j in range(k):
            total += term
            term = term * xd / (j + 1)
        return float((-xd).exp() * total)


@pytest.mark.parametrize("q", PROBABILITIES)
def test_two_degrees_of_freedom_are_the_exponential_distribution(q):
    assert chi2_ppf(q, 2) == pytest.approx(-2.0 * math.log1p(-q), rel=1e-15, abs=0)
    assert chi2_isf(q, 2) == pytest.approx(-2.0 * math.log(q), rel=1e-15)
    x = chi2_isf(q, 2)
    assert chi2_sf(x, 2) == pytest.approx(q, rel=1e-13)


@pytest.mark.parametrize("alpha", [0.3, 0.05, 1e-3, 1e-9, 1e-50, 1e-100])
def test_one_degree_of_freedom_is_the_square_of_a_normal(alpha):
    exact = NormalDist().inv_cdf(alpha / 2) ** 2
    assert chi2_isf(alpha, 1) == pytest.approx(exact, rel=2e-15)


def test_a_tiny_lower_quantile_of_one_degree_of_freedom_is_q_squared_pi_over_two():
    # P(chi2(1) <= x) = erf(sqrt(x / 2)) ~ sqrt(2 x / pi) for tiny x
    assert chi2_ppf(1e-100, 1) == pytest.approx(1e-200 * math.pi / 2, rel=2e-15)


@pytest.mark.parametrize("k", [1, 2, 3, 10, 29, 75, 200])
@pytest.mark.parametrize("ratio", [0.01, 0.5, 0.9, 1.0, 1.1, 2.0, 5.0])
def test_whole_shapes_match_the_exact_finite_sum(k, ratio):
    x = k * ratio
    exact = _upper_tail_exact(k, x)
    tol = 1e-14 if exact > 1e-30 else 3e-13  # far tails: the exponent's rounding, |log Q| ulps
    assert gamma_q(k, x) == pytest.approx(exact, rel=tol)
    assert gamma_p(k, x) == pytest.approx(1.0 - exact, rel=1e-14, abs=1e-15)


@pytest.mark.parametrize("dof", DOFS)
def test_quantiles_agree_with_scipy_special(dof):
    for q in PROBABILITIES:
        assert chi2_ppf(q, dof) == pytest.approx(2.0 * special.gammaincinv(0.5 * dof, q), rel=5e-14)
        assert chi2_isf(q, dof) == pytest.approx(2.0 * special.gammainccinv(0.5 * dof, q), rel=5e-14)


@pytest.mark.parametrize("dof", DOFS)
def test_tails_agree_with_scipy_special(dof):
    for x in np.linspace(0.01, 4.0 * dof + 30.0, 41):
        for mine, theirs in ((chi2_cdf(x, dof), special.gammainc(0.5 * dof, 0.5 * x)),
                             (chi2_sf(x, dof), special.gammaincc(0.5 * dof, 0.5 * x))):
            # scipy's own error reaches 1e-12 for large shapes (the exact sums above hold ours)
            assert mine == pytest.approx(theirs, rel=2e-12, abs=1e-300)


def test_quantile_and_distribution_function_are_inverse():
    for dof in (1, 6, 58):
        for q in (1e-6, 0.025, 0.5, 0.975):
            assert chi2_cdf(chi2_ppf(q, dof), dof) == pytest.approx(q, rel=1e-13)


def test_far_tail_keeps_its_relative_precision():
    # 2000 with 3 degrees of freedom: P(X > x) ~ 1e-433 underflows; 700 does not
    assert chi2_sf(700.0, 3) == pytest.approx(special.gammaincc(1.5, 350.0), rel=1e-13)
    assert chi2_sf(700.0, 3) > 0.0
    assert chi2_sf(2000.0, 3) == 0.0


@pytest.mark.parametrize("x", [1e5, 1e100, 1e300, 1.7e308])
def test_huge_arguments_give_the_limits_without_overflow(x):
    for dof in (1, 6, 58):
        assert chi2_cdf(x, dof) == 1.0 and chi2_sf(x, dof) == 0.0
    assert gamma_p(0.5, x) == 1.0 and gamma_q(3.0, x) == 0.0


def test_the_ends_of_the_probability_range():
    assert chi2_ppf(0.0, 4) == 0.0 and chi2_ppf(1.0, 4) == math.inf
    assert chi2_isf(1.0, 4) == 0.0 and chi2_isf(0.0, 4) == math.inf
    assert chi2_cdf(0.0, 4) == 0.0 and chi2_sf(0.0, 4) == 1.0
    assert chi2_cdf(math.inf, 4) == 1.0 and chi2_sf(math.inf, 4) == 0.0
    assert math.isnan(chi2_cdf(math.nan, 4)) and math.isnan(chi2_sf(math.nan, 4))


@pytest.mark.parametrize("call, words", [
    (lambda: chi2_ppf(1.5, 3), "probability in [0, 1], got 1.5"),
    (lambda: chi2_isf(math.nan, 3), "probability in [0, 1], got nan"),
    (lambda: chi2_ppf(0.5, 0), "degrees of freedom > 0, got 0.0"),
    (lambda: chi2_sf(1.0, math.inf), "degrees of freedom > 0, got inf"),
    (lambda: gamma_p(-1.0, 1.0), "shape a > 0, got -1.0"),
    (lambda: gamma_q(1.0, -2.0), "x >= 0, got -2.0"),
])
def test_bad_arguments_are_refused_by_name(call, words):
    with pytest.raises(ValueError, match=words.replace("[", r"\[").replace("]", r"\]")):
        call()


def test_logsumexp_equals_scipy_special_bit_for_bit():
    rng = np.random.default_rng(5)
    for shape, axis in [((1000,), None), ((50, 7), 1), ((7, 50), 0), ((3,), None)]:
        a = rng.normal(size=shape) * 50.0
        a.flat[1] = a.flat[2] = a.max()  # a tie at the maximum
        assert np.array_equal(logsumexp(a, axis=axis, keepdims=True),
                              special.logsumexp(a, axis=axis, keepdims=True))
        assert np.array_equal(logsumexp(a, axis=axis), special.logsumexp(a, axis=axis))


def test_logsumexp_neither_overflows_nor_underflows():
    assert logsumexp([1000.0, 1000.0]) == pytest.approx(1000.0 + math.log(2.0), rel=1e-16)
    assert logsumexp([-1000.0, -1000.0]) == pytest.approx(-1000.0 + math.log(2.0), rel=1e-16)


def test_logsumexp_of_infinities_nan_and_nothing():
    assert logsumexp([-math.inf, -math.inf]) == -math.inf
    assert logsumexp([]) == -math.inf
    assert logsumexp([math.inf, 1.0]) == math.inf
    assert math.isnan(logsumexp([math.nan, 1.0]))
    assert logsumexp([1.0, -math.inf]) == 1.0
    rows = logsumexp(np.array([[-math.inf, -math.inf], [0.0, 0.0]]), axis=1)
    assert rows[0] == -math.inf and rows[1] == pytest.approx(math.log(2.0), rel=1e-16)
