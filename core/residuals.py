"""Per-measurement residuals and NIS, the consistency a run reports with or without a truth.

:class:`ResidualObserver` is an observer of every run (like the custody observer). Before each
update the prior belief predicts the measurement (:func:`cistrack.consistency.innovation`);
after the update it writes into the step's metrics, so that each update row of ``steps.parquet``
holds, for every measured component NAME (the sensor's names: azimuth/elevation, ra/dec):

    res_NAME_arcsec   z - z_hat, the residual of the observation against the prior's predicted
                      measurement (arcsec; azimuth wrapped at ±180 deg); a component whose name
                      contains "range" is a range: res_NAME_km
    sd_NAME_arcsec    sqrt of the diagonal of S = P_zz + R, the residual's predicted 1-sigma
                      (sd_NAME_km for a range)
    nis, nis_dof      nu^T S^-1 nu and the number of components m (chi^2(m) if consistent);
                      for a step of several sites' measurements at one time, stacked (res_ and
                      sd_ then hold the first measurement's components)
    nis_outside_95    1 when the NIS lies outside the central 95 % of chi^2(m), else 0

:func:`residual_summary` summarises a run's rows for the CLI: mean NIS against its chi-square
bounds, the share of measurements outside the per-measurement 95 % bounds (5 % if consistent)
and the largest absolute angle residual (arcsec).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .hookspecs import hookimpl
from .units import LU_KM

__all__ = ["ResidualObserver", "residual_columns", "ResidualSummary", "residual_summary", "ARCSEC_PER_RAD"]

ARCSEC_PER_RAD = 180.0 / np.pi * 3600.0


def _unit(name: str) -> tuple[str, float]:
    return ("km", LU_KM) if "range" in name else ("arcsec", ARCSEC_PER_RAD)


def residual_columns(inn) -> dict[str, float]:
    """The step-table columns (see the module docstring) of a
    :class:`cistrack.consistency.Innovation`."""
    from .consistency import chi2_ppf  # scipy.stats.chi2.ppf's value without importing scipy.stats

    m = len(inn.names)
    nis = inn.nis
    sd = np.sqrt(np.maximum(np.diag(inn.s), 0.0))
    out: dict[str, float] = {}
    for name, nu, s in zip(inn.names, inn.nu, sd):
        unit, scale = _unit(name)
        if f"res_{name}_{unit}" in out:  # several sites at one time: the columns hold the first's
            continue
        out[f"res_{name}_{unit}"] = float(nu * scale)
        out[f"sd_{name}_{unit}"] = float(s * scale)
    lo, hi = chi2_ppf(0.025, m), chi2_ppf(0.975, m)
    out.update({"nis": nis, "nis_dof": float(m),
                "nis_outside_95": float(not lo <= nis <= hi) if np.isfinite(nis) else float("nan")})
    return out


class ResidualObserver:
    """Lifecycle observer adding the residual columns to each update step's metrics."""

    def __init__(self) -> None:
        self._pending: dict[int, dict[str, float]] = {}

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        if step.kind != "update" or step.measurement is None:
            return
        from .consistency import innovation

        try:
            self._pending[step.index] = residual_columns(innovation(step.belief, step.group or step.measurement,
                                                                    run.sensor))
        except (np.linalg.LinAlgError, ValueError):
            self._pending.pop(step.index, None)

    @hookimpl(tryfirst=True)
    def cistrack_step_updated(self, run, step) -> None:
        cols = self._pending.pop(step.index, None)
        if cols is not None:
            step.metrics.update(cols)


@dataclass(frozen=True)
class ResidualSummary:
    """Measurement consistency of a run's updates.

    Attributes
    ----------
    nis_test : cistrack.consistency.NisTest    mean NIS and its chi-square bounds
    n : int                                    updates with a finite NIS
    share_outside_95 : float                   share of them outside the per-measurement 95 % bounds
    max_abs_residual_arcsec : float            largest |residual| of an angle (arcsec; NaN if none)
    """

    nis_test: Any
    n: int
    share_outside_95: float
    max_abs_residual_arcsec: float


def residual_summary(rows: list[dict[str, Any]], level: float = 0.95) -> ResidualSummary:
    """The :class:`ResidualSummary` of a run's step rows (dicts, see :mod:`cistrack.step_table`);
    updates of different sizes (several sites at one time) are tested with the summed dof."""
    from .consistency import nis_test

    ups = [r for r in rows if r.get("kind") == "update" and r.get("nis") is not None
           and np.isfinite(r["nis"]) and (r.get("nis_dof") or 0) > 0]
    test = nis_test([r["nis"] for r in ups], [int(r["nis_dof"]) for r in ups], level)
    res = [abs(v) for r in ups for k, v in r.items()
           if k.startswith("res_") and k.endswith("_arcsec") and v is not None and np.isfinite(v)]
    return ResidualSummary(test, len(ups), float(np.mean([r["nis_outside_95"] for r in ups])) if ups else float("nan"),
                           max(res) if res else float("nan"))
