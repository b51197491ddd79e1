"""Which measurements an IOD method fits: the first part of the first pass.

The first pass is the run of measurements before the first gap longer than ``pass_gap_hours``.
Of its n measurements the first ``ceil(fit_fraction * n)`` are fitted, clipped to
``min_fit .. max_fit`` (and never more than n). Everything is checked before any sampling so that
a bad measurement set fails with a message that says what is missing.
"""
from __future__ import annotations

import math

import numpy as np

from cistrack.errors import IODError
from cistrack.units import hours_to_tu, tu_to_hours

__all__ = ["first_pass_length", "select_fit_indices"]


def _validated_times(times) -> np.ndarray:
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.shape[0] == 0:
        raise IODError("no measurements: IOD needs the measurements of a first pass")
    if not np.all(np.isfinite(t)):
        raise IODError("measurement times contain NaN or infinity")
    if t.shape[0] > 1 and np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise IODError(f"measurement times must increase strictly; measurement {i + 1} "
                       f"(t = {t[i + 1]:.6g} TU) is not after measurement {i} (t = {t[i]:.6g} TU)")
    return t


def first_pass_length(times, pass_gap_hours: float) -> int:
    """Number of measurements before the first gap longer than ``pass_gap_hours``.

    times : (K,) TU, strictly increasing.
    """
    t = _validated_times(times)
    gaps = np.diff(t)
    big = np.nonzero(gaps > float(hours_to_tu(pass_gap_hours)))[0]
    return int(big[0] + 1) if big.size else int(t.shape[0])


def select_fit_indices(times, *, pass_gap_hours: float = 3.0, fit_fraction: float = 0.5,
                       min_fit: int = 8, max_fit: int = 12, order: int = 4) -> np.ndarray:
    """Indices (J,) of the measurements to fit, J in [min_fit, max_fit], all in the first pass.

    Raises IODError when the first pass has fewer than ``min_fit`` measurements or fewer than
    ``order + 1`` (a polynomial of order p needs p + 1 points).
    """
    t = _validated_times(times)
    n_pass = first_pass_length(t, pass_gap_hours)
    need = max(min_fit, order + 1)
    if n_pass < need:
        span = tu_to_hours(t[n_pass - 1] - t[0])
        raise IODError(
            f"the first pass has {n_pass} measurement(s) over {span:.2f} h (before the first gap "
            f"longer than {pass_gap_hours} h); IOD needs at least {need} (min_fit = {min_fit}, "
            f"polynomial order {order} needs {order + 1}). Task more measurements in the first "
            f"pass or lower min_fit/order.", settings=("min_fit", "order"))
    n_fit = math.ceil(fit_fraction * n_pass - 1e-9)
    n_fit = int(min(max(n_fit, min_fit), max_fit, n_pass))
    if n_fit < order + 1:  # max_fit < order + 1 is refused by the component; kept as a guard
        raise IODError(f"only {n_fit} measurements selected; order {order} needs {order + 1}")
    return np.arange(n_fit)
