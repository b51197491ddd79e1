"""Per-measurement residuals and NIS, the consistency a run reports with or without a truth.

:class:`ResidualMetric` is the metric stage ``residuals`` of every run. At the prior of each
update the belief predicts the measurement (:func:`cistrack.evaluation.consistency.innovation`);
at the posterior the stage adds the columns to the step's metrics, so that each update row of
``steps.parquet`` holds, for every measured component NAME (the sensor's names: azimuth/elevation,
ra/dec):

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

from cistrack.evaluation.metric_stage import StepMetric
from cistrack.units import LU_KM
from cistrack._moved import renamed_names

__all__ = ["ResidualMetric", "residual_columns", "ResidualSummary", "residual_summary", "ARCSEC_PER_RAD",
           "CONSISTENCY_KEYS", "consistency_summary", "pool_consistency", "consistency_text"]

ARCSEC_PER_RAD = 180.0 / np.pi * 3600.0


def _unit(name: str) -> tuple[str, float]:
    return ("km", LU_KM) if "range" in name else ("arcsec", ARCSEC_PER_RAD)


def residual_columns(inn) -> dict[str, float]:
    """The step-table columns (see the module docstring) of a
    :class:`cistrack.evaluation.consistency.Innovation`."""
    from cistrack.least_squares.chi_square import chi2_ppf  # scipy.stats.chi2.ppf's value without importing scipy.stats

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


class ResidualMetric(StepMetric):
    """Metric stage ``residuals``: the residual columns of each update step (see the module docstring)."""

    name = "residuals"

    def __init__(self) -> None:
        self._pending: dict[int, dict[str, float]] = {}

    def compute(self, run, step, event: str) -> dict[str, float]:
        """Nothing at the prior of an update (the innovation is kept for the posterior), the
        columns at its posterior; nothing for other steps."""
        if step.kind != "update" or step.measurement is None:
            return {}
        if event == "updated":
            return self._pending.pop(step.index, None) or {}
        from cistrack.evaluation.consistency import innovation

        try:
            self._pending[step.index] = residual_columns(innovation(step.belief, step.group or step.measurement,
                                                                    run.sensor))
        except (np.linalg.LinAlgError, ValueError):
            self._pending.pop(step.index, None)
        return {}


@dataclass(frozen=True)
class ResidualSummary:
    """Measurement consistency of a run's updates.

    Attributes
    ----------
    nis_test : cistrack.evaluation.consistency.NisTest    mean NIS and its chi-square bounds
    n : int                                    updates with a finite NIS
    share_outside_95 : float                   share of them outside the per-measurement 95 % bounds
    max_abs_residual_arcsec : float            largest |residual| of an angle (arcsec; NaN if none)
    max_abs_residual_sd_arcsec : float         the predicted standard deviation of that residual (arcsec):
                                               a large residual is no fault where the belief predicted it
    max_abs_residual_t_days : float            its time (days since the epoch)
    max_residual_sigma : float                 largest |residual| / predicted standard deviation of any angle
    """

    nis_test: Any
    n: int
    share_outside_95: float
    max_abs_residual_arcsec: float
    max_abs_residual_sd_arcsec: float = float("nan")
    max_abs_residual_t_days: float = float("nan")
    max_residual_sigma: float = float("nan")


def residual_summary(rows: list[dict[str, Any]], level: float = 0.95) -> ResidualSummary:
    """The :class:`ResidualSummary` of a run's step rows (dicts, see :mod:`cistrack.results.step_table`);
    updates of different sizes (several sites at one time) are tested with the summed dof."""
    from cistrack.evaluation.consistency import nis_test

    ups = [r for r in rows if r.get("kind") == "update" and r.get("nis") is not None
           and np.isfinite(r["nis"]) and (r.get("nis_dof") or 0) > 0]
    test = nis_test([r["nis"] for r in ups], [int(r["nis_dof"]) for r in ups], level)
    res = [(abs(v), _finite(r.get("sd_" + k[4:])), _finite(r.get("t_days"))) for r in ups for k, v in r.items()
           if k.startswith("res_") and k.endswith("_arcsec") and v is not None and np.isfinite(v)]
    largest = max(res, default=(float("nan"),) * 3)
    normalised = [a / sd for a, sd, _ in res if sd > 0]
    return ResidualSummary(test, len(ups), float(np.mean([r["nis_outside_95"] for r in ups])) if ups else float("nan"),
                           *largest, max(normalised, default=float("nan")))


def _finite(v) -> float:
    return float(v) if v is not None and np.isfinite(v) else float("nan")


CONSISTENCY_KEYS: tuple[str, ...] = (
    "nis_mean", "nis_updates", "nis_dof", "nis_dof_total", "nis_lower", "nis_upper", "level", "nis_within",
    "share_outside_95", "max_abs_residual_arcsec", "max_abs_residual_sd_arcsec", "max_abs_residual_t_days",
    "max_residual_sigma")
"""Keys of :func:`consistency_summary` (the manifest's ``summary.consistency``)."""


def _finite_or_none(v):
    return None if v is None or not np.isfinite(v) else float(v)


def consistency_summary(rows: list[dict[str, Any]], level: float = 0.95) -> dict[str, Any]:
    """A run's measurement consistency as plain JSON data (the manifest's ``summary.consistency``):

    nis_mean, nis_updates          mean NIS over the updates with a finite NIS, and how many
    nis_dof                        components per update (int; a float mean when sizes differ)
    nis_dof_total                  summed components (the chi-square dof of the summed NIS)
    nis_lower, nis_upper, level    two-sided ``level`` chi-square bounds of the mean NIS
    nis_within                     whether the mean lies within them (None without an update)
    share_outside_95               share of updates whose NIS is outside its own 95 % bounds
    max_abs_residual_arcsec        largest |angle residual| (arcsec)
    max_abs_residual_sd_arcsec     the predicted standard deviation of that residual (arcsec)
    max_abs_residual_t_days        its time (days since the epoch)
    max_residual_sigma             largest |angle residual| / its predicted standard deviation

    NaN is stored as None."""
    rs = residual_summary(rows, level)
    nt = rs.nis_test
    dof_total = int(sum(int(r["nis_dof"]) for r in rows if r.get("kind") == "update" and r.get("nis") is not None
                        and np.isfinite(r["nis"]) and (r.get("nis_dof") or 0) > 0))
    return {"nis_mean": _finite_or_none(nt.mean), "nis_updates": int(nt.n),
            "nis_dof": nt.dof if nt.n else None, "nis_dof_total": dof_total,
            "nis_lower": _finite_or_none(nt.lower), "nis_upper": _finite_or_none(nt.upper), "level": level,
            "nis_within": bool(nt.within) if nt.n else None,
            "share_outside_95": _finite_or_none(rs.share_outside_95),
            "max_abs_residual_arcsec": _finite_or_none(rs.max_abs_residual_arcsec),
            "max_abs_residual_sd_arcsec": _finite_or_none(rs.max_abs_residual_sd_arcsec),
            "max_abs_residual_t_days": _finite_or_none(rs.max_abs_residual_t_days),
            "max_residual_sigma": _finite_or_none(rs.max_residual_sigma)}


def pool_consistency(summaries: list[dict[str, Any]]) -> dict[str, Any]:
    """The :func:`consistency_summary` of several runs' updates together (a study's group), from
    the runs' own summaries: the mean NIS over all their updates, tested against chi-square with
    the summed dof; the share outside weighted by updates; the largest residual of all."""
    from cistrack.least_squares.chi_square import chi2_ppf

    parts = [c for c in summaries if c and c.get("nis_updates")]
    level = parts[0].get("level", 0.95) if parts else 0.95
    k = sum(int(c["nis_updates"]) for c in parts)
    if not k:
        return {**dict.fromkeys(CONSISTENCY_KEYS), "nis_updates": 0, "nis_dof_total": 0, "level": level}
    total = sum(int(c["nis_dof_total"]) for c in parts)
    mean = sum(c["nis_mean"] * c["nis_updates"] for c in parts) / k
    a = 1.0 - level
    lo, hi = chi2_ppf(a / 2, total) / k, chi2_ppf(1 - a / 2, total) / k
    dofs = {c["nis_dof"] for c in parts}
    shares = [(c["share_outside_95"], c["nis_updates"]) for c in parts if c.get("share_outside_95") is not None]
    res = [c for c in parts if c.get("max_abs_residual_arcsec") is not None]
    worst = max(res, key=lambda c: c["max_abs_residual_arcsec"], default={})
    sigmas = [c["max_residual_sigma"] for c in parts if c.get("max_residual_sigma") is not None]
    return {"nis_mean": mean, "nis_updates": k,
            "nis_dof": dofs.pop() if len(dofs) == 1 and isinstance(next(iter(dofs)), int) else total / k,
            "nis_dof_total": total, "nis_lower": lo, "nis_upper": hi, "level": level,
            "nis_within": bool(lo <= mean <= hi),
            "share_outside_95": sum(s * n for s, n in shares) / sum(n for _, n in shares) if shares else None,
            "max_abs_residual_arcsec": worst.get("max_abs_residual_arcsec"),
            "max_abs_residual_sd_arcsec": worst.get("max_abs_residual_sd_arcsec"),
            "max_abs_residual_t_days": worst.get("max_abs_residual_t_days"), "max_residual_sigma": max(sigmas, default=None)}


def consistency_text(c: dict[str, Any]) -> str:
    """One line a person reads about a :func:`consistency_summary` (no word about custody)."""
    if not c or not c.get("nis_updates"):
        return "no update with a finite NIS"
    dof = c["nis_dof"]
    each = f"{dof} components each" if isinstance(dof, int) else f"{dof:.3g} components on average"
    ok = "consistent" if c["nis_within"] else "INCONSISTENT"
    share = c.get("share_outside_95")
    return (f"mean NIS {c['nis_mean']:.3g} over {c['nis_updates']} updates ({each}), {c['level']:.0%} chi-square "
            f"bounds [{c['nis_lower']:.3g}, {c['nis_upper']:.3g}]: {ok}; "
            + ("-" if share is None else f"{100 * share:.0f} %") + " of measurements outside their 95 % NIS "
            "bounds (5 % if consistent); " + _largest_residual_text(c))


def _largest_residual_text(c: dict[str, Any]) -> str:
    """The largest residual beside the spread the belief predicted for it, and the largest in sigmas:
    an early residual of degrees under a wide IOD cloud is no inconsistency."""
    res, sd, t = (c.get(k) for k in ("max_abs_residual_arcsec", "max_abs_residual_sd_arcsec", "max_abs_residual_t_days"))
    text = "largest |residual| " + ("-" if res is None else f"{res:.3g}") + " arcsec"
    if res is not None and sd is not None:
        text += f" (predicted sigma {sd:.3g} arcsec there" + ("" if t is None else f", t = {t:.3g} d") + ")"
    sigma = c.get("max_residual_sigma")
    return text + ("" if sigma is None else f"; largest |residual| / predicted sigma {sigma:.3g}")


__getattr__ = renamed_names(__name__, {"ResidualObserver": ("ResidualMetric", ResidualMetric)})  # the old name, for one release
