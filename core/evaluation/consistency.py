"""Measurement consistency without a truth: the normalised innovation squared (NIS).

Before each update the prior belief predicts the measurement: its particles pushed through the
sensor give the predicted mean z_hat (circular on angles) and covariance P_zz; with the noise R,
S = P_zz + R and the innovation nu = z - z_hat (angles wrapped),

    NIS = nu^T S^-1 nu  ~  chi^2(m)    for a consistent filter (m measured components).

Over K updates the sum is chi^2(mK): :func:`nis_test` gives the two-sided bounds on the mean
NIS, (chi2.ppf(a/2, mK) / K, chi2.ppf(1 - a/2, mK) / K), and whether the run lies within them.

:class:`Innovation` and :func:`innovation` live in :mod:`cistrack.model.innovation` (plugins use
them); this module re-exports the same objects.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.least_squares.chi_square import chi2_ppf  # re-exported: the quantile lives with the least squares
from cistrack.model.innovation import MAX_NIS_SAMPLES, Innovation, _block_diagonal, innovation  # noqa: F401  (moved to the model so plugins can use it)

__all__ = ["Innovation", "innovation", "innovation_nis", "nis_test", "NisTest", "MAX_NIS_SAMPLES", "run_nis_test",
           "chi2_ppf"]


def innovation_nis(prior, measurement, sensor) -> tuple[float, int]:
    """NIS of ``measurement`` (a :class:`cistrack.model.measurement.Measurement` or a sequence of
    them at one time, see :func:`innovation`) under the ``prior`` belief, measured by
    ``sensor``: returns (NIS, m)."""
    inn = innovation(prior, measurement, sensor)
    return inn.nis, len(inn.names)


@dataclass(frozen=True)
class NisTest:
    """Mean NIS over ``n`` updates of ``dof`` components each, its two-sided ``level`` bounds,
    and whether the mean lies within them."""

    mean: float
    n: int
    dof: int | float
    lower: float
    upper: float
    level: float

    @property
    def within(self) -> bool:
        return self.lower <= self.mean <= self.upper


def nis_test(nis, dof, level: float = 0.95) -> NisTest:
    """Chi-square test of the mean of ``nis`` values (K,), each chi^2(dof) if consistent; ``dof``
    is one int or one per value (updates stacking several sites' measurements differ in size):
    the sum is chi^2 with the summed dof. ``NisTest.dof`` is the int when all agree, else the
    mean number of components per update (a float)."""
    v = np.asarray(nis, dtype=float)
    d = np.broadcast_to(np.asarray(dof), v.shape)
    keep = np.isfinite(v)
    v, d = v[keep], d[keep]
    k = v.size
    if k == 0:
        return NisTest(float("nan"), 0, int(np.max(dof, initial=0)), float("nan"), float("nan"), level)
    total = int(np.sum(d))
    same = bool(np.all(d == d[0]))
    a = 1.0 - level
    return NisTest(float(v.mean()), k, int(d[0]) if same else total / k, float(chi2_ppf(a / 2, total) / k),
                   float(chi2_ppf(1 - a / 2, total) / k), level)


def run_nis_test(run_dir, level: float = 0.95) -> NisTest:
    """The NIS test of a run directory's update steps (``estimates.parquet``)."""
    from cistrack.results.estimates import read_estimates
    est = read_estimates(run_dir)
    if est.nis is None:
        return nis_test([], 0, level)
    ok = np.isfinite(est.nis) & (est.nis_dof > 0)
    return nis_test(est.nis[ok], est.nis_dof[ok], level)
