"""The special functions a run evaluates, in the standard library and NumPy: the regularised
incomplete gamma functions, the chi-square distribution's tails and quantiles, and log-sum-exp.

scipy.special has them too, but importing it costs about 0.1 s of CPU in every process (its
array-API layer imports numpy.f2py and numpy.testing), a tenth of a whole ``cistrack run
example-1``. These agree with scipy.special to about 1e-14 relative
(tests/core/test_special_functions.py) and with closed forms (chi-square with 2 degrees of
freedom is exponential).

The incomplete gamma functions follow the textbook scheme: the power series of P(a, x) below
x = a + 1, the continued fraction of Q(a, x) above it (modified Lentz), each times the prefix
x^a e^-x / Gamma(a), whose logarithm is taken about x = a with Stirling's series for a >= 10 so
that it keeps its relative precision for large ``a``. Quantiles are Newton's method on the
logarithm of the smaller tail, kept inside a bracket.
"""
from __future__ import annotations

import math
from functools import lru_cache
from statistics import NormalDist

import numpy as np

__all__ = ["gamma_p", "gamma_q", "chi2_cdf", "chi2_sf", "chi2_ppf", "chi2_isf", "logsumexp"]

_EPS = 2.220446049250313e-16
_TINY = 1e-300
_MAX_TERMS = 100_000
_NEWTON_DONE = 1e-13
"""A Newton step this small (relative) leaves an error of its square: the quantile is done."""
_STIRLING = (1.0 / 12.0, -1.0 / 360.0, 1.0 / 1260.0, -1.0 / 1680.0, 1.0 / 1188.0, -691.0 / 360360.0,
             1.0 / 156.0)
"""Coefficients of a^-1, a^-3, ..., a^-13 in lgamma(a) - ((a - 1/2) log a - a + log(2 pi) / 2)."""
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


def _check(a: float, x: float) -> tuple[float, float]:
    a, x = float(a), float(x)
    if not (a > 0.0 and math.isfinite(a)):
        raise ValueError(f"the incomplete gamma function needs a finite shape a > 0, got {a!r}")
    if math.isnan(x) or x < 0.0:
        raise ValueError(f"the incomplete gamma function needs x >= 0, got {x!r}")
    return a, x


def _log_ratio_minus(x: float, a: float) -> float:
    """log(x / a) - (x - a) / a, accurate also for x near a (x, a > 0)."""
    t = (x - a) / a
    if t < -0.5:
        r = x / a
        return (math.log(r) if r > 1e-300 else math.log(x) - math.log(a)) - t
    if abs(t) >= 0.25:
        return math.log1p(t) - t
    total, power, n = 0.0, -t * t, 2
    while True:  # the series sum over n >= 2 of (-1)^(n+1) t^n / n
        term = power / n
        total += term
        if abs(term) <= _EPS * abs(total):
            return total
        power *= -t
        n += 1


def _stirling_correction(a: float) -> float:
    inv, inv2, total = 1.0 / a, 1.0 / (a * a), 0.0
    for c in _STIRLING:
        total += c * inv
        inv *= inv2
    return total


def _prefix(a: float, x: float) -> float:
    """x^a e^-x / Gamma(a), for x > 0 (0.0 where it underflows). Products where they neither
    overflow nor underflow (a logarithm's rounding would grow with its size); else the logarithm,
    taken about x = a with Stirling's series for a >= 10."""
    if a < 10.0 and x < 700.0 and abs(a * math.log(x)) < 660.0:
        return x ** a * math.exp(-x) / math.gamma(a)
    return math.exp(_log_prefix(a, x))


def _log_prefix(a: float, x: float) -> float:
    """log(x^a e^-x / Gamma(a)), for x > 0."""
    if a < 10.0:
        return a * math.log(x) - x - math.lgamma(a)
    return (a * _log_ratio_minus(x, a) + 0.5 * math.log(a) - _HALF_LOG_2PI
            - _stirling_correction(a))


def _series(a: float, x: float) -> float:
    """The sum over n >= 0 of x^n / ((a+1)...(a+n)); P(a, x) is this times prefix / a."""
    term = total = 1.0
    for n in range(1, _MAX_TERMS):
        term *= x / (a + n)
        total += term
        if term <= total * _EPS:
            return total
    raise ArithmeticError(f"the incomplete gamma series did not converge (a={a!r}, x={x!r})")


def _continued_fraction(a: float, x: float) -> float:
    """Q(a, x) / prefix by the modified Lentz method (x >= a + 1)."""
    b = x + 1.0 - a
    c, d = 1.0 / _TINY, 1.0 / b
    h = d
    for i in range(1, _MAX_TERMS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = _TINY if abs(d) < _TINY else d
        c = b + an / c
        c = _TINY if abs(c) < _TINY else c
        d = 1.0 / d
        step = d * c
        h *= step
        if abs(step - 1.0) <= _EPS:
            return h
    raise ArithmeticError(f"the incomplete gamma continued fraction did not converge (a={a!r}, x={x!r})")


def _tails(a: float, x: float) -> tuple[float, float]:
    """(P(a, x), Q(a, x)); the smaller one carries the full relative precision."""
    if x == 0.0:
        return 0.0, 1.0
    if math.isinf(x):
        return 1.0, 0.0
    prefix = _prefix(a, x)
    if x < a + 1.0:
        p = prefix / a * _series(a, x)
        return p, 1.0 - p
    q = prefix * _continued_fraction(a, x)
    return 1.0 - q, q


def gamma_p(a: float, x: float) -> float:
    """The regularised lower incomplete gamma function P(a, x) (scipy.special.gammainc)."""
    return _tails(*_check(a, x))[0]


def gamma_q(a: float, x: float) -> float:
    """The regularised upper incomplete gamma function Q(a, x) = 1 - P(a, x), with its full
    relative precision far in the tail (scipy.special.gammaincc)."""
    return _tails(*_check(a, x))[1]


def _check_dof(dof: float) -> float:
    dof = float(dof)
    if not (dof > 0.0 and math.isfinite(dof)):
        raise ValueError(f"chi-square needs finite degrees of freedom > 0, got {dof!r}")
    return dof


def chi2_cdf(x: float, dof: float) -> float:
    """P(X <= x) for X ~ chi-square(dof); NaN for a NaN ``x``."""
    dof = _check_dof(dof)
    return math.nan if math.isnan(x) else gamma_p(0.5 * dof, 0.5 * max(float(x), 0.0))


def chi2_sf(x: float, dof: float) -> float:
    """P(X > x) for X ~ chi-square(dof), accurate far in the tail; NaN for a NaN ``x``."""
    dof = _check_dof(dof)
    return math.nan if math.isnan(x) else gamma_q(0.5 * dof, 0.5 * max(float(x), 0.0))


def _start(a: float, p: float, upper: bool) -> float:
    """A first guess of x with the tail P (lower) or Q (upper) of Gamma(a) equal to p: the
    Wilson-Hilferty cube, or where that is not positive the leading term of the tail."""
    z = NormalDist().inv_cdf(p) * (-1.0 if upper else 1.0)
    h = 1.0 / (9.0 * a)
    x = a * (1.0 - h + z * math.sqrt(h)) ** 3
    if x > 0.0:
        return x
    return max(a, -math.log(p)) if upper else math.exp((math.log(p) + math.lgamma(a + 1.0)) / a)


@lru_cache(maxsize=1024)
def _gamma_quantile(a: float, p: float, upper: bool) -> float:
    """x with P(a, x) = p (``upper`` False) or Q(a, x) = p (True), for 0 < p <= 1/2."""
    target = math.log(p)
    lo, hi = 0.0, math.inf
    x = _start(a, p, upper)
    if x == 0.0:  # the quantile lies below the smallest double
        return 0.0
    for _ in range(200):
        lower_tail, upper_tail = _tails(a, x)
        tail = upper_tail if upper else lower_tail
        if tail <= 0.0:  # underflowed: x lies beyond the quantile
            lo, hi = (lo, x) if upper else (x, hi)
            x = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * x
            continue
        ratio = tail / p
        g = math.log(ratio) if 0.0 < ratio < math.inf else math.log(tail) - target  # log(p) can be large
        if (g > 0.0) == upper:
            lo = x
        else:
            hi = x
        # d log(tail) / dx, in size (capped: a step from a vanishing tail is bracketed anyway)
        slope = math.exp(min(_log_prefix(a, x) - math.log(x) - math.log(tail), 700.0))
        new = x + g / slope if upper else x - g / slope
        if abs(new - x) <= _NEWTON_DONE * x:  # the next step would be below the tails' rounding
            return new
        if not (lo < new < hi and math.isfinite(new)):
            new = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * x
        x = new
    raise ArithmeticError(f"the gamma quantile did not converge (a={a!r}, p={p!r})")


def _quantile(p: float, dof: float, upper: bool) -> float:
    dof = _check_dof(dof)
    p = float(p)
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"a chi-square quantile needs a probability in [0, 1], got {p!r}")
    if p == (1.0 if upper else 0.0):
        return 0.0
    if p == (0.0 if upper else 1.0):
        return math.inf
    if p > 0.5:  # 1 - p is exact here: solve in the smaller tail, the other side's
        return 2.0 * _gamma_quantile(0.5 * dof, 1.0 - p, not upper)
    return 2.0 * _gamma_quantile(0.5 * dof, p, upper)


def chi2_ppf(q: float, dof: float) -> float:
    """x with P(X <= x) = q for X ~ chi-square(dof) (scipy.stats.chi2.ppf)."""
    return _quantile(q, dof, upper=False)


def chi2_isf(alpha: float, dof: float) -> float:
    """x with P(X > x) = alpha for X ~ chi-square(dof), accurate for tiny alpha (no 1 - alpha
    rounding; scipy.stats.chi2.isf)."""
    return _quantile(alpha, dof, upper=True)


def logsumexp(a: np.ndarray, axis: int | None = None, keepdims: bool = False) -> np.ndarray | float:
    """log(sum(exp(a))) over ``axis`` (every element when None) without overflow or underflow.

    With M the largest element and m the number of elements equal to it, the sum is
    m e^M (1 + s) where s is the sum of exp(a - M) over the other elements divided by m, so the
    result is M + log(m) + log1p(s): no term overflows and a sum dominated by its largest term
    keeps its precision. -inf where every element is -inf or there is none, +inf where one is
    +inf, NaN where one is NaN. A float for ``axis=None`` without ``keepdims``, else an array
    (the input's shape less ``axis``, or with it kept as 1)."""
    a = np.asarray(a, dtype=float)
    top = np.max(a, axis=axis, keepdims=True, initial=-math.inf)
    is_top = a == top
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ties = np.sum(is_top, axis=axis, keepdims=True, dtype=float)
        rest = np.sum(np.where(is_top, 0.0, np.exp(a - top)), axis=axis, keepdims=True) / ties
        out = np.log1p(rest) + np.log(ties) + top
        out = np.where(np.isfinite(top), out, np.log(np.sum(np.exp(a), axis=axis, keepdims=True)))
    if not keepdims:
        out = np.squeeze(out) if axis is None else np.squeeze(out, axis=axis)
    return float(out) if out.ndim == 0 else out
