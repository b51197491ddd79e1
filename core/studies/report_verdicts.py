"""The verdict parts of a study report: every run that did not track, with its reason, and each
filter's custody side by side.

- :func:`flagged_runs` lists every run whose verdict is not-converged, lost, diverged (degenerate
  weights, collapsed belief, error far beyond sigma, left cislunar space) or filter-failed, with
  the reason its verdict gives; the report prints them in the terminal and the Markdown, and
  ``runs.csv`` (:func:`write_runs_csv`) holds every run's verdict and reason, one row per run.
- :func:`custody_by_filter` gives, per scenario and IOD variant, each filter's custody count and
  rate with its Wilson 95 % interval in one row (Markdown, terminal and ``custody_by_filter.csv``).

A run without a truth is flagged only when it diverged or failed; nothing about it names custody.
"""
from __future__ import annotations

import csv
from pathlib import Path

from cistrack.results.atomic_files import atomic_target

__all__ = ["FLAGGED_KINDS", "flagged_runs", "flagged_line", "write_runs_csv", "RUN_COLUMNS",
           "custody_by_filter", "custody_markdown", "custody_text", "write_custody_by_filter"]

FLAGGED_KINDS: tuple[str, ...] = ("not-converged", "lost", "diverged", "filter-failed")
"""Verdict kinds a report lists run by run with their reason (all but tracking and no-truth)."""

RUN_COLUMNS: tuple[str, ...] = ("scenario", "iod", "filter", "seed", "run_id", "status", "has_truth", "verdict",
                                "reason", "verdict_step", "verdict_t_days", "final_pos_err_km", "final_nees",
                                "final_max_sigma_km", "mean_nis")
"""Columns of ``runs.csv``, one row per finished run."""


def _max_sigma(final: dict) -> float | None:
    vals = [final[k] for k in ("sigma_x_km", "sigma_y_km", "sigma_z_km") if final.get(k) is not None]
    return max(vals) if vals else None


def flagged_runs(groups: dict) -> list[dict]:
    """The runs of ``groups`` ((scenario, iod, filter) -> list of RunSummary) whose verdict is one
    of :data:`FLAGGED_KINDS`, in group order, as dicts (scenario, iod, filter, run_id, kind,
    reason, step, t_days)."""
    out = []
    for (sc, iod, flt), sums in sorted(groups.items()):
        for x in sums:
            if x.verdict.kind in FLAGGED_KINDS:
                out.append({"scenario": sc, "iod": iod, "filter": flt, "run_id": x.run_id, "kind": x.verdict.kind,
                            "reason": x.verdict.reason, "step": x.verdict.step, "t_days": x.verdict.t_days})
    return out


def flagged_line(f: dict) -> str:
    """One line (Markdown list item) about a flagged run: its verdict, reason, step and time."""
    at = f" (step {f['step']}, t = {f['t_days']:.3g} d)" if f["t_days"] is not None else ""
    return f"- {f['run_id']} ({f['filter']} with {f['iod']} IOD on {f['scenario']}): {f['kind']}: {f['reason']}{at}"


def write_runs_csv(groups: dict, path: Path) -> Path:
    """Write ``runs.csv``: every run's verdict, reason and final figures (:data:`RUN_COLUMNS`)."""
    with atomic_target(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(RUN_COLUMNS))
        w.writeheader()
        for (sc, iod, flt), sums in sorted(groups.items()):
            for x in sorted(sums, key=lambda s: s.seed):
                w.writerow({"scenario": sc, "iod": iod, "filter": flt, "seed": x.seed, "run_id": x.run_id,
                            "status": x.status, "has_truth": x.has_truth, "verdict": x.verdict.kind,
                            "reason": x.verdict.reason, "verdict_step": x.verdict.step,
                            "verdict_t_days": x.verdict.t_days, "final_pos_err_km": x.final.get("pos_err_km"),
                            "final_nees": x.final.get("nees"), "final_max_sigma_km": _max_sigma(x.final),
                            "mean_nis": (x.consistency or {}).get("nis_mean")})
    return path


def custody_by_filter(rows: list[dict]) -> tuple[list[str], list[tuple[str, str]], dict[tuple[str, str], dict]]:
    """Each filter's custody side by side, from the report's rows (with ``custody_kept``, ``runs``,
    ``custody_ci_lo``, ``custody_ci_hi``; rows without a truth are left out).

    Returns (filters in first-seen order, the (scenario, iod) pairs, and per pair a dict filter ->
    cell text "k/n = rate [lo-hi], tracking t": custody kept counts not-converged runs too (a
    cloud too wide to be a track), so the number of tracking runs stands beside it)."""
    filters: list[str] = []
    pairs: list[tuple[str, str]] = []
    cells: dict[tuple[str, str], dict] = {}
    for r in rows:
        if r.get("custody_kept") is None:
            continue
        if r["filter"] not in filters:
            filters.append(r["filter"])
        key = (r["scenario"], r["iod"])
        if key not in cells:
            pairs.append(key)
            cells[key] = {}
        tracking = r.get("tracking_runs")
        cells[key][r["filter"]] = (f"{r['custody_kept']}/{r['runs']} = {r['custody_rate']:.2f} "
                                   f"[{r['custody_ci_lo']:.2f}-{r['custody_ci_hi']:.2f}]"
                                   + (f", tracking {tracking}" if tracking is not None else ""))
    return filters, pairs, cells


def custody_markdown(rows: list[dict]) -> list[str]:
    """The Markdown table of :func:`custody_by_filter` (empty without a row with a truth)."""
    filters, pairs, cells = custody_by_filter(rows)
    if not pairs:
        return []
    head = ["scenario", "iod", *filters]
    out = ["## Custody by filter (kept/runs = rate [Wilson 95 % interval], runs tracking)", "",
           "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join([sc, iod, *(cells[(sc, iod)].get(f, "-") for f in filters)]) + " |" for sc, iod in pairs]
    return out + [""]


def custody_text(rows: list[dict]) -> list[str]:
    """Terminal lines of :func:`custody_by_filter`, one per scenario and IOD variant."""
    filters, pairs, cells = custody_by_filter(rows)
    return [f"- {sc} / {iod}: " + "; ".join(f"{f} {cells[(sc, iod)][f]}" for f in filters if f in cells[(sc, iod)])
            for sc, iod in pairs]


def write_custody_by_filter(rows: list[dict], path: Path) -> Path | None:
    """Write ``custody_by_filter.csv`` (scenario, iod, then per filter its custody cell); None and
    no file when no row has a truth."""
    filters, pairs, cells = custody_by_filter(rows)
    if not pairs:
        return None
    with atomic_target(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["scenario", "iod", *(f"{f} custody [Wilson 95 %]" for f in filters)])
        for sc, iod in pairs:
            w.writerow([sc, iod, *(cells[(sc, iod)].get(f, "") for f in filters)])
    return path
