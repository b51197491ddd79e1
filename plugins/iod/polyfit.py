"""Least-squares polynomial fits in time, shared by every Monte Carlo sample.

All samples of a kinematic-fitting IOD are observed at the same K times, so the least-squares
problem of every sample and every coordinate has the same design matrix. The fitted value and
first derivative at an evaluation time are therefore *linear* functionals of the data,

    value(t_e)      = sum_k w0[k] * y[k]
    derivative(t_e) = sum_k w1[k] * y[k],

with weights that depend only on the times. :func:`evaluation_weights` computes them once and
:func:`fit_value_and_rate` applies them to all samples and coordinates in one matrix product.

Truncation error
----------------
The weights reproduce polynomials of degree <= p exactly. Expanding a smooth y(t) in a Taylor
series about t_e with Lagrange remainder, y(t) = P_p(t) + y^(p+1)(xi) (t - t_e)^(p+1) / (p+1)!,
gives for noise-free data

    |value error|      <= M / (p+1)! * sum_k |w0[k]| |t_k - t_e|^(p+1)
    |derivative error| <= M / (p+1)! * sum_k |w1[k]| |t_k - t_e|^(p+1)

where M = max |y^(p+1)| over the window. :func:`truncation_bounds` returns the two factors
multiplying M.
"""
from __future__ import annotations

import math

import numpy as np

from cistrack.errors import IODError

__all__ = ["evaluation_weights", "fit_value_and_rate", "truncation_bounds"]


def _check_times(times: np.ndarray, order: int) -> np.ndarray:
    t = np.asarray(times, dtype=float).reshape(-1)
    if not np.all(np.isfinite(t)):
        raise IODError("fit times contain NaN or infinity")
    if t.shape[0] < order + 1:
        raise IODError(f"a polynomial of order {order} needs at least {order + 1} measurements; "
                       f"got {t.shape[0]}")
    if t.shape[0] > 1 and np.any(np.diff(t) <= 0):
        raise IODError("fit times must increase strictly")
    return t


def evaluation_weights(times: np.ndarray, order: int, t_eval: float) -> np.ndarray:
    """Weights mapping data at ``times`` to the fitted value and rate at ``t_eval``.

    Parameters
    ----------
    times : (K,) float
        Sample times (any unit; the rate is per that unit), strictly increasing, K >= order + 1.
    order : int
        Polynomial order p >= 1.
    t_eval : float
        Evaluation time (usually the last sample time).

    Returns
    -------
    (2, K) float
        Row 0 gives the fitted value at ``t_eval``, row 1 its time derivative.
    """
    if order < 1:
        raise IODError(f"polynomial order must be >= 1 to give a velocity; got {order}")
    t = _check_times(times, order)
    # Centre on the evaluation time and scale by the window length: the Vandermonde matrix then
    # has entries in [-1, 1] and its least-squares solve is well conditioned for p <= ~10.
    scale = float(np.max(np.abs(t - t_eval)))
    if scale <= 0.0:
        raise IODError("fit window has zero length")
    tau = (t - t_eval) / scale
    vander = np.vander(tau, order + 1, increasing=True)  # (K, p+1): 1, tau, tau^2, ...
    pinv = np.linalg.pinv(vander)  # (p+1, K); coefficient c = pinv @ y
    w = pinv[:2].copy()  # value at tau=0 is c0; d/dtau at 0 is c1
    w[1] /= scale
    return w


def fit_value_and_rate(times: np.ndarray, values: np.ndarray, order: int,
                       t_eval: float) -> tuple[np.ndarray, np.ndarray]:
    """Fit every series in ``values`` by a polynomial of ``order`` and evaluate at ``t_eval``.

    Parameters
    ----------
    times : (K,) float
    values : (..., K, d) float
        Any number of leading sample axes; K samples in time; d coordinates.
    order : int
    t_eval : float

    Returns
    -------
    value, rate : (..., d) float each
        Fitted value and time derivative at ``t_eval`` (rate in value units per time unit).
    """
    w = evaluation_weights(times, order, t_eval)
    v = np.asarray(values, dtype=float)
    if v.ndim < 2 or v.shape[-2] != w.shape[1]:
        raise IODError(f"values shape {v.shape} does not have {w.shape[1]} times on axis -2")
    out = np.einsum("jk,...kd->j...d", w, v, optimize=True)
    return out[0], out[1]


def truncation_bounds(times: np.ndarray, order: int, t_eval: float) -> tuple[float, float]:
    """Factors (b0, b1) with |value error| <= b0·M and |rate error| <= b1·M for noise-free data,
    M = max |d^(p+1) y / dt^(p+1)| over the window (see the module docstring)."""
    t = np.asarray(times, dtype=float).reshape(-1)
    w = evaluation_weights(t, order, t_eval)
    rem = np.abs(t - t_eval) ** (order + 1) / math.factorial(order + 1)
    return float(np.abs(w[0]) @ rem), float(np.abs(w[1]) @ rem)
