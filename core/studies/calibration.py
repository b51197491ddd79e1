"""Calibration statistics of a group of runs (one filter x IOD variant of a study).

A filter is calibrated when its stated uncertainty matches its actual error. Over the R runs of
a group (one per seed) a study report gives:

- the custody rate k/R with its Wilson score interval (95 %): with p = k/R and z the normal
  quantile, centre (p + z^2/2R) / (1 + z^2/R), half-width z sqrt(p(1-p)/R + z^2/4R^2) / (1 + z^2/R);
- ANEES, the mean of the runs' final NEES: for a consistent filter R * ANEES ~ chi^2(6R), so the
  two-sided 95 % bounds are chi2.ppf(0.025, 6R) / R and chi2.ppf(0.975, 6R) / R;
- the truth's final highest-density level (0 at the mode, 1 far outside): uniform on [0, 1] for
  a consistent belief; its Kolmogorov-Smirnov statistic and p-value against uniform;
- the number of diverged runs (verdict ``diverged``, see :mod:`cistrack.evaluation.verdicts`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

__all__ = ["wilson_interval", "anees_bounds", "uniformity_ks", "GroupCalibration", "group_calibration",
           "NEES_DOF", "LEVEL"]

NEES_DOF = 6
"""Degrees of freedom of the NEES of a 6-D state."""
LEVEL = 0.95
"""Confidence level of every interval and bound of the report."""


def wilson_interval(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """Wilson score interval (lower, upper), both in [0, 1], of a binomial proportion: ``k``
    successes in ``n`` trials (n >= 1, 0 <= k <= n) at confidence ``level``."""
    if n < 1 or not 0 <= k <= n:
        raise ValueError(f"Wilson interval needs 0 <= k <= n and n >= 1, got k={k}, n={n}")
    from scipy.stats import norm

    z = float(norm.ppf(0.5 + 0.5 * level))
    p = k / n
    den = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / den
    return max(0.0, centre - half), min(1.0, centre + half)


def anees_bounds(n_runs: int, dof: int = NEES_DOF, level: float = LEVEL) -> tuple[float, float]:
    """Two-sided ``level`` bounds on the mean of ``n_runs`` independent chi^2(``dof``) NEES values:
    (chi2.ppf(a/2, dof n) / n, chi2.ppf(1 - a/2, dof n) / n) with a = 1 - level."""
    if n_runs < 1:
        raise ValueError(f"ANEES bounds need at least one run, got {n_runs}")
    from scipy.stats import chi2

    a = 1.0 - level
    return (float(chi2.ppf(a / 2, dof * n_runs) / n_runs),
            float(chi2.ppf(1.0 - a / 2, dof * n_runs) / n_runs))


def uniformity_ks(values: Iterable[float]) -> tuple[float, float]:
    """Kolmogorov-Smirnov statistic and p-value of ``values`` (in [0, 1]) against the uniform
    distribution on [0, 1]; (NaN, NaN) without a finite value."""
    v = np.asarray([x for x in values if x is not None], dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan
    from scipy.stats import kstest

    res = kstest(v, "uniform")
    return float(res.statistic), float(res.pvalue)


@dataclass(frozen=True)
class GroupCalibration:
    """Calibration of one group of runs (see the module docstring).

    Attributes
    ----------
    runs : int                       runs in the group
    custody_kept : int               runs that kept custody (verdict tracking or not-converged)
    custody_lo, custody_hi : float   Wilson 95 % interval of the custody rate
    final_anees : float              mean final NEES over the runs with a finite one (NaN if none)
    final_anees_runs : int           how many runs it averages
    final_anees_lo, final_anees_hi   its chi-square 95 % bounds for a consistent filter
    hdr_ks, hdr_ks_p : float         KS statistic and p-value of the final truth HDR levels vs U(0, 1)
    hdr_runs : int                   runs with a final HDR level
    hdr_above_099 : float            share of those with a level above 0.99 (1 % if calibrated)
    diverged : int                   runs whose verdict is ``diverged``
    """

    runs: int
    custody_kept: int
    custody_lo: float
    custody_hi: float
    final_anees: float
    final_anees_runs: int
    final_anees_lo: float
    final_anees_hi: float
    hdr_ks: float
    hdr_ks_p: float
    hdr_runs: int
    hdr_above_099: float
    diverged: int

    @property
    def anees_within(self) -> bool | None:
        """Whether the final ANEES lies within its bounds (None without a finite NEES)."""
        if self.final_anees_runs == 0:
            return None
        return self.final_anees_lo <= self.final_anees <= self.final_anees_hi


def group_calibration(summaries: list) -> GroupCalibration:
    """The :class:`GroupCalibration` of run summaries (:class:`cistrack.evaluation.run_summary.RunSummary`,
    at least one): custody from their verdicts, NEES and HDR level from ``final`` of the runs that
    ended normally (``ended_normally``: not those whose filter raised)."""
    n = len(summaries)
    if n == 0:
        raise ValueError("calibration of an empty group of runs")
    kept = sum(1 for s in summaries if s.custody_kept)
    lo, hi = wilson_interval(kept, n)
    ended = [s for s in summaries if s.ended_normally]  # a filter that raised has no final state
    nees = np.asarray([s.final.get("nees", math.nan) for s in ended], dtype=float)
    nees = nees[np.isfinite(nees)]
    a_lo, a_hi = anees_bounds(nees.size) if nees.size else (math.nan, math.nan)
    hdr = np.asarray([s.final.get("hdr_level", math.nan) for s in ended], dtype=float)
    hdr = hdr[np.isfinite(hdr)]
    ks, p = uniformity_ks(hdr)
    return GroupCalibration(
        runs=n, custody_kept=kept, custody_lo=lo, custody_hi=hi,
        final_anees=float(nees.mean()) if nees.size else math.nan, final_anees_runs=int(nees.size),
        final_anees_lo=a_lo, final_anees_hi=a_hi, hdr_ks=ks, hdr_ks_p=p, hdr_runs=int(hdr.size),
        hdr_above_099=float(np.mean(hdr > 0.99)) if hdr.size else math.nan,
        diverged=sum(1 for s in summaries if s.verdict.kind == "diverged"))
