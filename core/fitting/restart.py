"""Where the least squares of ``cistrack fit`` starts again when the filter's final estimate fails.

The fit starts from the filter's final estimate (:mod:`.from_observations`). A gross outlier that
the filter takes in (one observation a degree off, say) can send the filter astray, and the least
squares then starts from an estimate that does not fit the arc, or cannot even be propagated over
it (it hits the Moon). The filter's own estimates before that update are still good, and the least
squares' outlier rejection (:mod:`.outliers`) removes the bad observation once it starts from one
of them. :func:`restart_points` lists those estimates, read from the run's ``estimates.parquet``
(:mod:`cistrack.results.estimates`): the estimate just before each run of consecutive updates
whose normalised innovation squared (NIS, under the filter's prior) exceeds the
:data:`NIS_TAIL` tail of chi-square, latest run first.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Restart", "restart_points", "NIS_TAIL", "MAX_RESTARTS"]

NIS_TAIL = 1e-4
"""Tail probability of chi-square (degrees of freedom: the update's measurement components) above
which an update's NIS marks it as one the filter should not have taken in (18.4 for az/el)."""
MAX_RESTARTS = 2
"""At most this many restarts are listed (each costs a least-squares fit)."""


@dataclass(frozen=True)
class Restart:
    """A filter estimate to start the least squares from: ``step`` and ``utc`` of the estimate,
    ``t`` (TU), ``mean`` (6,) and ``covariance`` (6, 6) in the dynamics' nondimensional synodic
    units, and ``why``: the update after it that the filter should not have taken in."""

    step: int
    utc: str
    t: float
    mean: np.ndarray
    covariance: np.ndarray
    why: str


def restart_points(directory: str | Path, max_restarts: int = MAX_RESTARTS) -> list[Restart]:
    """The filter estimates of the run in ``directory`` to restart the least squares from (see the
    module docstring); empty when the run wrote no estimates or no update's NIS is that large."""
    from scipy.stats import chi2

    from cistrack.results.estimates import KM_SCALE, read_estimates

    try:
        est = read_estimates(directory)
    except FileNotFoundError:
        return []
    if est.nis is None or est.nis_dof is None:
        return []
    updates = [i for i in range(len(est.step)) if est.kind[i] == "update" and est.nis_dof[i] > 0
               and np.isfinite(est.nis[i])]
    limit = {i: float(chi2.isf(NIS_TAIL, est.nis_dof[i])) for i in updates}
    starts = [k for k, i in enumerate(updates) if est.nis[i] > limit[i]
              and (k == 0 or est.nis[updates[k - 1]] <= limit[updates[k - 1]])]
    out = []
    scale = np.multiply.outer(KM_SCALE, KM_SCALE)
    for k in reversed(starts):
        i = updates[k]
        if i == 0:
            continue
        j = i - 1
        why = (f"before the update at {est.utc[i][:19]}Z whose NIS {est.nis[i]:.3g} exceeds {limit[i]:.3g} "
               f"(chi-square with {est.nis_dof[i]} degrees of freedom, {NIS_TAIL:g} tail)")
        out.append(Restart(int(est.step[j]), str(est.utc[j])[:19] + "Z", float(est.t_tu[j]),
                           est.mean_km[j] / KM_SCALE, est.covariance_km[j] / scale, why))
        if len(out) >= max_restarts:
            break
    return out
