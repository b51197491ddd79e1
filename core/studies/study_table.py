"""One row per finished run of a study: what :class:`cistrack.api.StudyResult` shows as its table.

Each row names the run (scenario, filter, IOD, seed, run id), says how it ended (status, verdict
and its reason, custody) and gives its final metrics (per-axis sigmas in km and cm/s, errors in km
and m/s, NEES, entropy) and its wall time; ``summary`` holds the whole run summary (a dict, as in
``manifest.json``) and ``directory`` the run's folder.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from cistrack.results.store import read_manifest
from cistrack.studies.resume import is_done

__all__ = ["FINAL_COLUMNS", "study_rows"]

#: The final metrics a row carries (missing ones, e.g. errors of a run without a truth, are None).
FINAL_COLUMNS: tuple[str, ...] = ("pos_err_km", "vel_err_ms", "nees", "entropy", "sigma_x_km", "sigma_y_km",
                                  "sigma_z_km", "sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms")


def study_rows(specs: Iterable[Any]) -> list[dict[str, Any]]:
    """The rows of the runs of ``specs`` (:class:`cistrack.studies.study.RunSpec`) that are done on
    disk, in the order of ``specs``; runs that are not done have no row."""
    rows = []
    for s in specs:
        if not is_done(s.out_dir):
            continue
        summary = read_manifest(s.out_dir).get("summary")
        if not isinstance(summary, dict):
            continue
        verdict = summary.get("verdict") or {}
        final = summary.get("final") or {}
        rows.append({"scenario": s.scenario_name, "filter": s.filter_label, "iod": s.iod_label, "seed": s.seed,
                     "run_id": s.run_id, "status": summary.get("status"), "verdict": verdict.get("kind"),
                     "reason": verdict.get("reason"), "custody_kept": summary.get("custody_kept"),
                     **{k: final.get(k) for k in FINAL_COLUMNS}, "wall_time_s": summary.get("wall_time_s"),
                     "directory": s.out_dir, "summary": summary})
    return rows
