"""The final verdict of a run, decided once at its end from the last step's metrics.

During a run :class:`~cistrack.evaluation.custody.CustodyMetric` only knows "kept", "lost" and
"filter-failed". At the end :func:`final_verdict` makes it honest, with the thresholds of the
scenario's :class:`~cistrack.evaluation.custody.CustodyRule`:

- "filter-failed" stays as it is;
- "diverged", with or without a truth, when the normalised innovations blew up (NIS above
  ``blowup_nis`` on ``blowup_nis_updates`` consecutive updates: the step and time are those of
  the first), when a particle filter's weights degenerated (effective sample size or distinct
  particles below ``degenerate_ess`` at an update: the reason says where; the earlier of the two
  is reported), when the belief collapsed (largest
  position sigma below ``collapse_sigma_km`` or entropy not finite), when (with a truth only)
  the final error exceeds ``diverged_error_km`` with a NEES above ``diverged_nees``, or when the
  mean is farther than ``max_earth_distance_km`` from Earth;
- without a truth, "diverged" also when the median NIS of the last ``diverged_nis_updates``
  updates exceeds ``diverged_nis`` (the measurements fall far outside the predicted spread);
- no truth, and none of these: "no-truth" (the CLI reports measurement consistency, the NIS,
  instead of custody; a truthless run never speaks of custody, whatever its verdict);
- "lost" as the custody rule decided;
- "not-converged" when custody is kept but the largest position sigma exceeds ``precision_km``;
- "tracking" otherwise.
"""
from __future__ import annotations

import math
import statistics
from typing import Any

from cistrack.evaluation.custody import CustodyRule, Verdict
from cistrack.interfaces.filter import diagnostic_column

__all__ = ["final_verdict", "verdict_lines"]


def _last_update(rows: list[dict[str, Any]]) -> dict[str, Any]:
    updates = [r for r in rows if r.get("kind") == "update"]
    return updates[-1] if updates else (rows[-1] if rows else {})


_ESS, _UNIQUE, _N = (diagnostic_column(k) for k in ("ess_before_resampling", "unique_particles", "n_particles"))


def _degenerate(rows: list[dict[str, Any]], rule: CustodyRule) -> tuple[str, dict[str, Any]] | None:
    """The reason and row of the first update where a particle filter's weights degenerated: its
    effective sample size (``diag_ess_before_resampling``) or the number of distinct particles
    left (``diag_unique_particles``: resampling duplicates the few heavy ones, so the ESS of the
    next updates looks healthy again) is below ``rule.degenerate_ess``; None if there is none."""
    for r in rows:
        if r.get("kind") != "update":
            continue
        ess, unique = r.get(_ESS), r.get(_UNIQUE)
        low_ess = ess is not None and math.isfinite(ess) and ess < rule.degenerate_ess
        few = unique is not None and math.isfinite(unique) and unique < rule.degenerate_ess
        if low_ess or few:
            n = r.get(_N)
            of = f" of {int(n)} particles" if n is not None and math.isfinite(n) else ""
            size = f"effective sample size {ess:.3g}{of}" if ess is not None else "weights"
            left = f", {int(unique)} distinct particles left" if unique is not None and math.isfinite(unique) else ""
            return f"degenerate weights ({size}{left}; fewer than {rule.degenerate_ess:g})", r
    return None


def _nis_blowup(rows: list[dict[str, Any]], rule: CustodyRule) -> tuple[str, dict[str, Any]] | None:
    """The reason and row of the first update of a sustained blow-up of the innovations: the
    first of ``rule.blowup_nis_updates`` consecutive updates whose NIS exceeds ``rule.blowup_nis``
    (an infinite NIS counts; updates without an NIS, or with NaN, neither count nor break the
    run); None if there is none."""
    start, count, worst = None, 0, 0.0
    for r in rows:
        if r.get("kind") != "update" or r.get("nis") is None or math.isnan(float(r["nis"])):
            continue
        nis = float(r["nis"])
        if nis > rule.blowup_nis:
            start, count, worst = (r if count == 0 else start), count + 1, max(worst, nis)
            if count >= rule.blowup_nis_updates:
                return (f"innovations blew up: NIS {float(start['nis']):.3g} at this update and above "
                        f"{rule.blowup_nis:g} on {count} consecutive updates (largest {worst:.3g}; a "
                        f"consistent filter's NIS is chi-square with a few degrees of freedom)", start)
        else:
            start, count, worst = None, 0, 0.0
    return None


def _nis_far(rows: list[dict[str, Any]], rule: CustodyRule) -> str | None:
    """The reason when the median NIS of the last ``rule.diverged_nis_updates`` updates with a
    finite NIS exceeds ``rule.diverged_nis`` (measurements far outside the predicted spread);
    None otherwise or with fewer such updates."""
    nis = [float(r["nis"]) for r in rows if r.get("kind") == "update" and r.get("nis") is not None
           and math.isfinite(r["nis"])][-rule.diverged_nis_updates:]
    if len(nis) < rule.diverged_nis_updates:
        return None
    med = statistics.median(nis)
    if med > rule.diverged_nis:
        return (f"measurements far outside the predicted spread: median NIS {med:.3g} over the last "
                f"{len(nis)} updates > {rule.diverged_nis:g}")
    return None


def final_verdict(verdict: Verdict, rows: list[dict[str, Any]], rule: CustodyRule, has_truth: bool,
                  earth_distance_km: float | None = None, truth_earth_distance_km: float | None = None) -> Verdict:
    """The run's final :class:`Verdict`.

    Parameters
    ----------
    verdict : the custody observer's verdict at the end of the run
    rows : the run's table rows (dicts with ``kind``, ``step``, ``t_days``, ``sigma_x_km`` ...,
        ``pos_err_km`` and ``nees`` with a truth, ``entropy``)
    rule : thresholds (see :class:`~cistrack.evaluation.custody.CustodyRule`)
    has_truth : whether the run had a truth
    earth_distance_km : distance of the last mean from Earth (km), if known
    truth_earth_distance_km : the truth's distance from Earth (km) at that step, if known: a mean
        beyond ``max_earth_distance_km`` is no divergence when the truth is beyond it too (an
        escaping object followed; the error and NEES rule judges such a run)

    Times: a run that keeps custody (tracking, not-converged) has no step or time; a run that
    was lost and then diverged keeps the step and time at which the custody rule first fired;
    otherwise the step and time are where the verdict's condition was found.
    """
    if verdict.kind == "filter-failed":
        return verdict
    final = _final_verdict(verdict, rows, rule, has_truth, earth_distance_km, truth_earth_distance_km)
    if final.kept:  # custody kept: no loss time (the verdict was judged on the last update)
        return Verdict(final.kind, final.reason + (f"; {verdict.reason}" if verdict.reason else ""))
    if verdict.kind == "lost" and verdict.step is not None and final.kind == "diverged" \
            and (final.step is None or verdict.step <= final.step):
        # lost first, then diverged: the loss time stays the time the custody rule fired
        return Verdict("diverged", f"{final.reason} (custody lost first at step {verdict.step}, "
                       f"t = {verdict.t_days:.3f} d: {verdict.reason})", verdict.step, verdict.t_days)
    return final


def _final_verdict(verdict: Verdict, rows: list[dict[str, Any]], rule: CustodyRule, has_truth: bool,
                   earth_distance_km: float | None, truth_earth_distance_km: float | None) -> Verdict:
    """:func:`final_verdict` before the loss time is settled."""
    last = _last_update(rows)
    step, t_days = last.get("step"), last.get("t_days")
    at = (int(step) if step is not None else None, float(t_days) if t_days is not None else None)
    sig = max((float(last[k]) for k in ("sigma_x_km", "sigma_y_km", "sigma_z_km") if k in last),
              default=math.nan)
    entropy = float(last.get("entropy", 0.0))
    collapsed = None
    if not math.isfinite(entropy):
        collapsed = f"belief collapsed: entropy {entropy} is not finite"
    elif not math.isfinite(sig) or sig < rule.collapse_sigma_km:
        collapsed = f"belief collapsed: largest position sigma {sig:.3g} km < {rule.collapse_sigma_km:g} km"
    found = [f for f in (_nis_blowup(rows, rule), _degenerate(rows, rule)) if f is not None]
    degenerate = min(found, key=lambda f: int(f[1]["step"])) if found else None  # the earlier
    if degenerate is not None:
        reason, row = degenerate
        return Verdict("diverged", reason + (f"; then {collapsed}" if collapsed else ""),
                       int(row["step"]), float(row["t_days"]))
    if collapsed:
        return Verdict("diverged", collapsed, *at)
    if has_truth:
        err, nees = float(last.get("pos_err_km", 0.0)), float(last.get("nees", 0.0))
        if err > rule.diverged_error_km and not nees <= rule.diverged_nees:
            return Verdict("diverged", f"error far beyond sigma: final position error {err:.4g} km > "
                           f"{rule.diverged_error_km:g} km with NEES {nees:.3g} > {rule.diverged_nees:g}", *at)
    truth_inside = truth_earth_distance_km is None or truth_earth_distance_km <= rule.max_earth_distance_km
    if earth_distance_km is not None and not earth_distance_km <= rule.max_earth_distance_km and truth_inside:
        return Verdict("diverged", f"left cislunar space: mean {earth_distance_km:.4g} km from Earth > "
                       f"{rule.max_earth_distance_km:g} km", *at)
    if not has_truth:
        far = _nis_far(rows, rule)
        if far is not None:
            return Verdict("diverged", far, *at)
        return Verdict("no-truth", "no truth: judged by measurement consistency (NIS)")
    if not verdict.kept:
        return verdict
    if sig > rule.precision_km:
        return Verdict("not-converged", f"consistent but not converged: largest position sigma "
                       f"{sig:.4g} km > {rule.precision_km:g} km", *at)
    return Verdict("tracking", f"consistent, largest position sigma {sig:.3g} km <= "
                   f"{rule.precision_km:g} km")


def verdict_lines(summary, run_dir=None, fmt=lambda v: f"{v:.3g}" if v is not None else "-") -> list[str]:
    """The lines a person reads about a run's verdict (the CLI's summary): the kind and reason,
    and custody for a run with a truth; for a run without one its verdict (no-truth, or diverged
    / filter-failed with the reason) and its measurement consistency from the summary (mean NIS
    against the chi-square bounds, share of measurements outside their 95 % bounds, largest
    residual; :func:`cistrack.evaluation.residuals.consistency_summary`), never custody. ``run_dir`` names
    where the per-measurement residuals are (``steps.parquet``)."""
    from cistrack.evaluation.residuals import consistency_summary, consistency_text

    v = summary.verdict
    at = f" at step {v.step} (t = {fmt(v.t_days)} d)" if v.kind in ("lost", "diverged") and v.step is not None else ""
    if not summary.has_truth:
        c = summary.consistency
        if not c and run_dir is not None:  # a summary written before it stored its consistency
            from cistrack.results.store import read_steps
            c = consistency_summary(read_steps(run_dir).to_pylist())
        head = ("  verdict: no-truth (no truth to compare against: judged by measurement consistency)"
                if v.kind == "no-truth" else f"  verdict: {v.kind}{at}" + (f": {v.reason}" if v.reason else "")
                + " (no truth to compare against)")
        where = f" (per measurement in {run_dir}/steps.parquet: res_*_arcsec, sd_*_arcsec, nis)" if run_dir else ""
        return [head, f"  measurement consistency: {consistency_text(c)}{where}"]
    lost_at = ("" if summary.custody_lost_step is None else f" at step {summary.custody_lost_step}") + (
        f" (t = {fmt(summary.custody_lost_t_days)} d)" if summary.custody_lost_t_days is not None
        else f" (the run ended {summary.status}, before it was judged)")
    custody = "kept" if summary.custody_kept else f"LOST{lost_at}"
    return [f"  verdict: {v.kind}{at}" + (f": {v.reason}" if v.reason else ""), f"  custody: {custody}"]
