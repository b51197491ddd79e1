"""Reports of a study: the table (terminal, CSV, Markdown) and PNG plots in ``<out>/report/``.

Reads every finished run of a study (its manifest's :class:`~cistrack.evaluation.run_summary.RunSummary`,
measurement consistency included, and its ``steps.parquet``) and groups them by scenario, IOD
variant and filter. Files: ``summary.csv`` (one row per group), ``summary.md``, ``runs.csv`` (every
run's verdict and reason) and ``custody_by_filter.csv`` (:mod:`cistrack.studies.report_verdicts`); the
plots are drawn by :mod:`cistrack.studies.report_plots` and :mod:`cistrack.studies.calibration_plots`. Two ANEES
figures are reported and named apart: over every update of every run (``anees_every_update``)
and over the runs' final states (``final_anees``, with its chi-square bounds). When any run has a
truth burn or a detected maneuver, a "Maneuvers" table (``maneuvers.csv``, summary.md, terminal;
:mod:`cistrack.studies.maneuver_scores`) and two figures (``maneuver_detection``,
``maneuver_false_alarms``) are added.
"""
from __future__ import annotations

import csv
import os
import shutil
from pathlib import Path

import numpy as np

from cistrack.studies.architectures import architectures_of
from cistrack.studies.calibration import LEVEL, group_calibration
from cistrack.errors import ConfigError
from cistrack.results.atomic_files import atomic_target, write_text_atomic
from cistrack.results.output_paths import single_results
from cistrack.results.store import read_manifest, read_steps
from cistrack.studies.efficiency import efficiency_text, group_efficiency
from cistrack.studies.terminal_table import terminal_table, wrap_lines
from cistrack.studies.report_verdicts import (custody_by_filter, custody_markdown, custody_text, flagged_line, flagged_runs, write_custody_by_filter, write_runs_csv)
from cistrack.evaluation.run_summary import RunSummary
from cistrack.studies.study import REPORT_FOLDER, plan_runs
from cistrack.studies.resume import is_done, run_state
from cistrack.studies.study_lock import running_study

__all__ = ["report_study"]


_COUNTED = ("tracking", "not-converged", "lost", "diverged")
"""Verdict kinds counted per filter x IOD in the report's ``verdicts`` column, in this order."""
_COUNTED_TRUTHLESS = ("no-truth", "diverged")
"""The same for a study without a truth (filter-failed runs are counted as ``failed``)."""
_FINALS = ("sigma_x_km", "sigma_y_km", "sigma_z_km", "sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms",
           "pos_err_km", "vel_err_ms", "entropy")
"""Final-state figures of each run, reported as the group's median."""


def _count_column(kind: str) -> str:
    """The summary.csv column counting the runs of a verdict kind: 'not-converged' -> 'not_converged_runs'."""
    return kind.replace("-", "_") + "_runs"


_TRUTH_COLUMNS = {"bound_pos_km", "efficiency_final", "efficiency_by_pass", "custody_kept", "custody_rate", "median_lost_day", "pos_err_km_p5", "pos_err_km_p95",
                  "anees_every_update", "anees_every_update_n", "custody_ci_lo", "custody_ci_hi", "final_anees",
                  "final_anees_runs", "final_anees_lo", "final_anees_hi", "final_anees_within", "hdr_ks", "hdr_ks_p",
                  "hdr_runs", "hdr_above_099", "diverged_runs", "pos_err_km", "vel_err_ms"}
"""summary.csv columns that need a truth: left out of a study without one."""
_VERDICTS_EXPLAINED = (
    "Verdicts (see cistrack.evaluation.verdicts): tracking = custody kept and the largest position sigma within the rule's "
    "precision; not-converged = custody kept by a cloud too wide to be a track; lost = the truth left the "
    "belief; diverged = a particle filter's weights degenerated, the belief collapsed, the error is far beyond "
    "sigma, or the mean left cislunar space; filter-failed = the filter raised an error.")


def _median(xs):
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    return float(np.median(xs)) if xs else None


def _spread(xs) -> tuple[float | None, float | None]:
    """5th and 95th percentiles of the finite values (None if there are none)."""
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    if not xs:
        return None, None
    lo, hi = np.percentile(xs, [5.0, 95.0])
    return float(lo), float(hi)


def _anees(tables) -> tuple[float | None, int]:
    """Average NEES over every update step of every run, and the number of updates averaged."""
    vals = []
    for t in tables:
        if "nees" not in t.column_names or "kind" not in t.column_names:
            continue
        nees = np.asarray(t.column("nees").to_numpy(zero_copy_only=False), dtype=float)
        kinds = t.column("kind").to_pylist()
        vals += [v for v, k in zip(nees, kinds) if k == "update" and np.isfinite(v)]
    return (float(np.mean(vals)) if vals else None), len(vals)


_CALIBRATION = ("custody_ci_lo", "custody_ci_hi", "final_anees", "final_anees_runs", "final_anees_lo",
                "final_anees_hi", "final_anees_within", "hdr_ks", "hdr_ks_p", "hdr_runs", "hdr_above_099",
                "diverged_runs")
"""CSV columns of :func:`cistrack.studies.calibration.group_calibration` (None for a group without a truth)."""


def _calibration_columns(sums: list[RunSummary]) -> dict:
    if not any(x.has_truth for x in sums):  # no truth: no custody, NEES or HDR level
        return dict.fromkeys(_CALIBRATION)
    c = group_calibration(sums)
    nan = lambda v: None if v != v else v  # noqa: E731  (NaN -> empty CSV cell)
    return {"custody_ci_lo": c.custody_lo, "custody_ci_hi": c.custody_hi, "final_anees": nan(c.final_anees),
            "final_anees_runs": c.final_anees_runs, "final_anees_lo": nan(c.final_anees_lo),
            "final_anees_hi": nan(c.final_anees_hi), "final_anees_within": c.anees_within,
            "hdr_ks": nan(c.hdr_ks), "hdr_ks_p": nan(c.hdr_ks_p), "hdr_runs": c.hdr_runs,
            "hdr_above_099": nan(c.hdr_above_099), "diverged_runs": c.diverged}


_CONSISTENCY = ("mean_nis", "nis_dof", "nis_lo", "nis_hi", "nis_updates", "nis_outside_95_share",
                "max_abs_residual_arcsec")
"""CSV columns of the measurement consistency of a group's updates (:mod:`cistrack.evaluation.residuals`)."""


def _consistency_columns(sums: list[RunSummary], tables: list) -> dict:
    """The group's measurement consistency, pooled from each run's manifest (``summary.consistency``;
    a run written before manifests stored it is summarised from its steps table)."""
    from cistrack.evaluation.residuals import consistency_summary, pool_consistency

    per_run = [x.consistency or consistency_summary(t.to_pylist() if "nis" in t.column_names else [])
               for x, t in zip(sums, tables)]
    c = pool_consistency(per_run)
    if not c["nis_updates"]:
        return dict.fromkeys(_CONSISTENCY)
    return {"mean_nis": c["nis_mean"], "nis_dof": c["nis_dof"], "nis_lo": c["nis_lower"], "nis_hi": c["nis_upper"],
            "nis_updates": c["nis_updates"], "nis_outside_95_share": c["share_outside_95"],
            "max_abs_residual_arcsec": c["max_abs_residual_arcsec"], "_consistency": c}


def _consistency_text(r: dict) -> str:
    from cistrack.evaluation.residuals import consistency_text

    return consistency_text(r.get("_consistency") or {})


def _g(v, spec: str = ".3g") -> str:
    return "-" if v is None else format(v, spec)


def _calibration_cells(r: dict) -> list[str]:
    """Markdown cells of one row's calibration (see :data:`_CALIBRATION`)."""
    if r["custody_ci_lo"] is None:
        return ["no truth", "-", "-", "-", "-"]
    within = {True: "within", False: "OUTSIDE", None: "-"}[r["final_anees_within"]]
    return [f"{r['custody_kept']}/{r['runs']} = {r['custody_rate']:.2f} [{r['custody_ci_lo']:.2f}-{r['custody_ci_hi']:.2f}]",
            f"{_g(r['final_anees'])} [{_g(r['final_anees_lo'])}-{_g(r['final_anees_hi'])}] {within} "
            f"({r['final_anees_runs']} runs)",
            f"D = {_g(r['hdr_ks'], '.2f')}, p = {_g(r['hdr_ks_p'], '.2g')} ({r['hdr_runs']} runs)",
            _g(None if r["hdr_above_099"] is None else 100 * r["hdr_above_099"], ".0f") + " %",
            str(r["diverged_runs"])]


def _calibration_markdown(rows: list[dict]) -> list[str]:
    head = ["scenario", "iod", "filter", "custody rate [Wilson 95 %]",
            "final-state ANEES: mean of the runs' last NEES [chi-square 95 % bounds]", "final truth HDR level vs uniform: KS",
            "HDR level > 0.99 (1 % if calibrated)", "diverged"]
    out = ["## Calibration", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join([r["scenario"], r["iod"], r["filter"], *_calibration_cells(r)]) + " |" for r in rows]
    return out + ["", f"A consistent filter has a final ANEES within its {LEVEL:.0%} chi-square(6 x runs) / runs "
                  "bounds and a final truth HDR level uniform on [0, 1] (KS p-value not small); the histograms "
                  "are in `*__hdr.png`. NEES over time (median and 5-95 % band across seeds, chi-square(6) "
                  "band drawn) is in the figure of each scenario and IOD."]


def _calibration_line(r: dict) -> str:
    if r["custody_kept"] is None:
        return f"{r['filter']} / {r['iod']} / {r['scenario']}: no truth (measurement consistency: {_consistency_text(r)})"
    cells = _calibration_cells(r)
    return (f"{r['filter']} / {r['iod']} / {r['scenario']}: custody {cells[0]}; final ANEES {cells[1]}; "
            f"HDR KS {cells[2]}; HDR > 0.99 {cells[3]}; diverged {cells[4]}")


def _plan(path_or_name, out_dir, settings, first_seed, n_seeds):
    """The study's data, run specs and output directory; a directory that 'study run' wrote is
    reported with the seeds it recorded, not the study file's full list."""
    data, specs, out = plan_runs(path_or_name, out_dir, settings, first_seed, n_seeds)
    if not Path(path_or_name).is_dir() and (out / "study.json").is_file():
        _check_same_study(out, data, path_or_name, "--out" if out_dir is not None else "the study directory")
        if first_seed is None and n_seeds is None:
            data, specs, out = plan_runs(out, out, settings)
    return data, specs, out


def _check_same_study(out: Path, data: dict, path_or_name, where: str) -> None:
    """ConfigError when the study directory ``out`` holds another study than ``path_or_name``
    (its ``study.json`` names another): 'study run' refuses to write there, and a report of it
    under this study's name would describe runs of the other."""
    from cistrack.results.output_paths import is_same_study, recorded_study
    from cistrack.studies.study_file import study_source

    source = study_source(path_or_name)
    name = str(data.get("name") or Path(source).stem)
    try:
        rec_name, rec_source = recorded_study(out / "study.json")
    except (OSError, ValueError):
        return  # unreadable: the runs are checked one by one
    if not is_same_study((rec_name, rec_source), name, source):
        other = rec_name if rec_name is not None else rec_source
        raise ConfigError(f"{where} {out}: holds another study ('{other}'), not '{name}': report it as "
                          f"'cistrack study report {out}' (the directory alone), or give this study's own directory")


def _finished_runs(specs) -> tuple[dict, dict, list[str], list[str]]:
    """(scenario, iod, filter) -> the finished runs' summaries, and -> their step tables; the ids of
    the runs not finished; and the ids of the finished runs made otherwise than the study now plans
    them (another scenario, settings, seed or input file: their fingerprint differs, as ``study
    run`` finds them), which are not reported either."""
    groups: dict[tuple[str, str, str], list[RunSummary]] = {}
    tables: dict[tuple[str, str, str], list] = {}
    missing_ids: list[str] = []
    stale_ids: list[str] = []
    for s in specs:
        state = run_state(s.out_dir, s.fingerprint)
        if state != "done":
            (stale_ids if state == "stale" else missing_ids).append(s.run_id)
            continue
        man = read_manifest(s.out_dir)
        groups.setdefault((s.scenario_name, s.iod_label, s.filter_label), []).append(RunSummary.from_dict(man["summary"]))
        tables.setdefault((s.scenario_name, s.iod_label, s.filter_label), []).append(read_steps(s.out_dir))
    return groups, tables, missing_ids, stale_ids


def _summary_columns(counted: tuple[str, ...], study_has_truth: bool) -> list[str]:
    """The columns of summary.csv, in order (a study without a truth names no truth column)."""
    cols = ["scenario", "architecture", "iod", "filter", "runs", "custody_kept", "custody_rate", "median_lost_day",
            "failed_runs", "verdicts", *_FINALS, "pos_err_km_p5", "pos_err_km_p95", "anees_every_update",
            "anees_every_update_n", "wall_time_s", "wall_time_s_p5", "wall_time_s_p95", *_CALIBRATION, *_CONSISTENCY,
            "bound_pos_km", "efficiency_final", "efficiency_by_pass"]
    cols[cols.index("verdicts") + 1:cols.index("verdicts") + 1] = [_count_column(k) for k in counted
                                                                  if _count_column(k) not in cols]
    if not study_has_truth:  # no truth anywhere: the CSV names no custody, NEES or HDR column
        cols = [c for c in cols if c not in _TRUTH_COLUMNS]
    return cols


def _group_row(key: tuple[str, str, str], sums: list[RunSummary], tables: list, architecture,
               counted: tuple[str, ...]) -> dict:
    """One row of the summary: a scenario x IOD x filter group of finished runs."""
    sc, iod, flt = key
    kept = sum(1 for x in sums if x.custody_kept)
    truthless = not any(x.has_truth for x in sums)    # no custody to speak of
    row = {"scenario": sc, "architecture": architecture, "iod": iod, "filter": flt, "runs": len(sums),
           "custody_kept": None if truthless else kept, "custody_rate": None if truthless else kept / len(sums),
           "median_lost_day": None if truthless else _median([x.custody_lost_t_days for x in sums
                                                              if not x.custody_kept]),
           "failed_runs": sum(1 for x in sums if x.status != "finished"),
           "verdicts": "/".join(str(sum(1 for x in sums if x.verdict.kind == k)) for k in counted),
           **{_count_column(k): sum(1 for x in sums if x.verdict.kind == k) for k in counted}}
    ended = [x for x in sums if x.ended_normally]  # a filter that raised has no final state
    for k in _FINALS:
        row[k] = _median([x.final.get(k) for x in ended])
    row["pos_err_km_p5"], row["pos_err_km_p95"] = _spread([x.final.get("pos_err_km") for x in ended])
    row["anees_every_update"], row["anees_every_update_n"] = _anees(tables)
    row["wall_time_s"] = _median([x.wall_time_s for x in sums])
    row["wall_time_s_p5"], row["wall_time_s_p95"] = _spread([x.wall_time_s for x in sums])
    row.update(_calibration_columns(sums))
    row.update(_consistency_columns(sums, tables))
    eff = group_efficiency(sums)
    row.update({"bound_pos_km": eff.bound_km, "efficiency_final": eff.final,
                "efficiency_by_pass": " ".join(f"{p}:{r:.4g}" for p, r in eff.by_pass.items()) or None,
                "efficiency_text": efficiency_text(eff)})
    return row


def _write_summary_csv(rows: list[dict], cols: list[str], path: Path) -> Path:
    with atomic_target(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return path


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _summary_table(rows: list[dict], has_truth: bool, counted: tuple[str, ...]) -> list[str]:
    """The Markdown table of the groups, one row each."""
    header = ["scenario", "iod", "filter", "custody" if has_truth else "truth",
              *(["lost at (d, median)"] if has_truth else []), "failed", "verdicts: " + " / ".join(counted),
              "sigma pos x/y/z km", "sigma vel x/y/z cm/s",
              *(["pos err km: median [5-95 %]", "ANEES over every update (6 = consistent)"] if has_truth else []),
              "entropy", "wall time s: median [5-95 %]"]
    lines = []
    for r in rows:
        lines.append([r["scenario"], r["iod"], r["filter"],
                      "no truth" if r["custody_kept"] is None else f"{r['custody_kept']}/{r['runs']}",
                      *([_fmt(r["median_lost_day"])] if has_truth else []), str(r["failed_runs"]), r["verdicts"],
                      "/".join(_fmt(r[k]) for k in ("sigma_x_km", "sigma_y_km", "sigma_z_km")),
                      "/".join(_fmt(r[k]) for k in ("sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms")),
                      *([f"{_fmt(r['pos_err_km'])} [{_fmt(r['pos_err_km_p5'])}-{_fmt(r['pos_err_km_p95'])}]",
                         f"{_fmt(r['anees_every_update'])} ({r['anees_every_update_n']} updates)"] if has_truth else []),
                      _fmt(r["entropy"]), f"{_fmt(r['wall_time_s'])} [{_fmt(r['wall_time_s_p5'])}-{_fmt(r['wall_time_s_p95'])}]"])
    md = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return md + ["| " + " | ".join(cells) + " |" for cells in lines]


def _verdict_line(r: dict) -> str:
    """One group's custody (or, without a truth, measurement consistency) as a list item."""
    if r["custody_kept"] is None:
        return (f"- {r['filter']} with {r['iod']} IOD on {r['scenario']}: no truth, measurement "
                f"consistency: {_consistency_text(r)}.")
    if r["custody_kept"] < r["runs"]:
        failed = r["runs"] - r["custody_kept"] - r[_count_column("lost")] - r[_count_column("diverged")]
        why = ", ".join([f"{r[_count_column(k)]} {k}" for k in ("lost", "diverged") if r[_count_column(k)]]
                        + ([f"{failed} filter-failed"] if failed else []))
        return (f"- {r['filter']} with {r['iod']} IOD on {r['scenario']} did not keep custody in "
                f"{r['runs'] - r['custody_kept']} of {r['runs']} runs ({why}; median day "
                f"{_fmt(r['median_lost_day'])}).")
    return f"- {r['filter']} with {r['iod']} IOD on {r['scenario']} kept custody in all {r['runs']} runs."


def _ids(ids: list[str], shown: int = 8) -> str:
    """The first ``shown`` run ids, and how many more."""
    return ", ".join(ids[:shown]) + (f", ... ({len(ids) - shown} more)" if len(ids) > shown else "")


def _title(name: str, n_runs: int, missing_ids: list[str], stale_ids: list[str], running: str | None = None) -> str:
    """The report's first line; ``running``: the holder of a ``study run`` running in the directory
    as the report is written (:func:`~cistrack.studies.study_lock.running_study`), or None."""
    title = f"Study '{name}': {n_runs - len(missing_ids) - len(stale_ids)} of {n_runs} runs complete"
    if running is not None:  # probe I3: a report of a study still running had read like the final one
        title += (f", reported while a 'cistrack study run'{running} was still running in this directory: runs were "
                  "in progress, and that study run removes this report when it ends ('cistrack study report' "
                  "then reports every run)")
    if missing_ids:
        rerun = "that study run is running them" if running is not None else \
            "'cistrack study run' with the same options runs them"
        title += f" (not finished: {_ids(missing_ids)}; {rerun})"
    if stale_ids:
        title += f" ({_STALE}: {_ids(stale_ids)})"
    return title


_STALE = ("not reported, made with another scenario, settings, seed or input file than the study now gives them; "
          "'cistrack study run' with the same options and --overwrite runs them again")


def _flagged_title(has_truth: bool) -> str:
    return "Runs that did not track" if has_truth else "Diverged and failed runs"


def _summary_markdown(title: str, rows: list[dict], has_truth: bool, counted: tuple[str, ...], architectures: dict,
                      verdicts: list[str], flagged: list[str]) -> str:
    """summary.md: the table, observers, custody, calibration, efficiency and flagged runs."""
    custody = (["## Custody", "", *verdicts, "",
                "Custody rule: lost at the first update where the truth's log-likelihood (km, km/s) "
                "is below the scenario's threshold, or the truth is outside the 99.7% highest-density "
                "region on consecutive updates (see cistrack.scenario.loading.CustodyRule)."] if has_truth else
               ["## Measurement consistency (no truth)", "", *verdicts])
    calibration = _calibration_markdown(rows) if has_truth else [
        "## Calibration", "", "None of these runs has a truth: calibration (NEES, HDR level) needs one."]
    explain = (_VERDICTS_EXPLAINED if has_truth else
               "Verdicts without a truth (see cistrack.evaluation.verdicts): no-truth = judged by measurement consistency "
               "only; diverged = a particle filter's weights degenerated, the belief collapsed or its mean left "
               "cislunar space.")
    diverged = ["", f"## {_flagged_title(has_truth)} (verdict and reason; every run in runs.csv)", "",
                *(flagged or ["None."]), "", explain]
    efficiency = (["", "## Efficiency against the information bound", "",
                   "RMS position error across runs / RMS of the posterior Cramer-Rao bound along the truth "
                   "(1 = the best the data allow; cistrack.evaluation.information_bound):", "",
                   *[f"- {r['filter']} with {r['iod']} IOD on {r['scenario']}: {r['efficiency_text']}" for r in rows]]
                  if has_truth else [])
    observers = ["## Observers", "", *[f"- {sc}: {a}" for sc, a in architectures.items()], ""]
    return "\n".join([f"# {title}", "", *_summary_table(rows, has_truth, counted), "", *observers,
                      *custody_markdown(rows), *calibration, *efficiency, "", *custody, *diverged])


def _terminal_text(title: str, rows: list[dict], has_truth: bool, counted: tuple[str, ...], verdicts: list[str],
                   flagged: list[str], runs_csv: Path) -> str:
    """The report as printed: the terminal table, custody, calibration, efficiency, flagged runs."""
    by_filter_text = custody_text(rows)
    return "\n".join(wrap_lines([title, *terminal_table(rows, has_truth, counted), "(every column: summary.md, summary.csv)"]
                     + [""] + verdicts
                     + ((["", "Custody by filter (kept/runs = rate [Wilson 95 %], runs tracking):"] + by_filter_text)
                        if len(custody_by_filter(rows)[0]) > 1 else [])
                     + ["", "Calibration (95 %; the final ANEES averages each run's last NEES):" if has_truth
                        else "Measurement consistency (95 %; no truth, so no calibration):"]
                     + [f"- {_calibration_line(r)}" for r in rows]
                     + (["", "Efficiency (RMS position error / RMS information bound; 1 = the best the data allow):"]
                        + [f"- {r['filter']} / {r['iod']} / {r['scenario']}: {r['efficiency_text']}" for r in rows]
                        if has_truth else [])
                     + ["", f"{_flagged_title(has_truth)} (verdict and reason; every run in {runs_csv}):"]
                     + (flagged or ["None."])))


def _figures(groups: dict, tables: dict, rows: list[dict], rep_dir: Path, name: str) -> list[Path]:
    """The report's figures: per scenario and IOD (report_plots) and the HDR histograms."""
    from cistrack.studies.report_plots import plot_study
    from cistrack.studies.calibration_plots import plot_hdr_histograms

    figures = {key: {"tables": tables[key], "summaries": [x.to_dict() for x in groups[key]]} for key in groups}
    files = plot_study(figures, rep_dir, name)
    return files + plot_hdr_histograms({k: v["summaries"] for k, v in figures.items()}, rep_dir,
                                       {(r["scenario"], r["iod"], r["filter"]): r for r in rows})


def _maneuver_rows(specs, groups: dict, tables: dict) -> list[dict]:
    """The "Maneuvers" rows (:mod:`cistrack.studies.maneuver_scores`), one per group; none when no
    run has a truth burn or a detection."""
    from cistrack.studies.maneuver_scores import GroupRuns, has_maneuvers, maneuver_rows

    sums = {k: [x.to_dict() for x in v] for k, v in groups.items()}
    if not has_maneuvers([s for v in sums.values() for s in v]):
        return []
    first = {}  # a finished run of each group: its sweep, and its directory for the response it ran
    for s in specs:
        if (s.scenario_name, s.iod_label, s.filter_label) not in first and is_done(s.out_dir):
            first[(s.scenario_name, s.iod_label, s.filter_label)] = s
    return maneuver_rows({k: GroupRuns(sums[k], tables[k], first[k].sweep, first[k].out_dir) for k in groups})


def _maneuver_report(man_rows: list[dict], rep_dir: Path, name: str) -> tuple[str, str, list[Path]]:
    """The maneuvers section of summary.md and of the terminal text, and its CSV and figures ("" and
    no file without maneuvers)."""
    if not man_rows:
        return "", "", []
    from cistrack.studies.maneuver_scores import maneuver_markdown, maneuver_text, write_maneuvers_csv
    from cistrack.studies.report_plots import plot_false_alarms, plot_maneuver_detection

    files = [write_maneuvers_csv(man_rows, rep_dir / "maneuvers.csv")]
    files += plot_maneuver_detection(man_rows, rep_dir, name) + plot_false_alarms(man_rows, rep_dir, name)
    return ("\n\n" + "\n".join(maneuver_markdown(man_rows)), "\n\n" + "\n".join(maneuver_text(man_rows)),
            files)


def report_study(path_or_name: str | Path, out_dir: str | Path | None = None,
                 settings: list[str] | None = None, first_seed: int | None = None,
                 n_seeds: int | None = None) -> dict:
    """Summarise a study: terminal text, summary.csv, summary.md and figures (PNG, SVG, PDF; see
    :mod:`cistrack.studies.report_plots`) in <out>/report/.

    Raises ConfigError (and writes nothing) when no run of the study has finished, and ConfigError
    naming the folder or file when the report cannot be written there (a read-only study
    directory, a full disk).
    """
    data, specs, out = _plan(path_or_name, out_dir, settings, first_seed, n_seeds)
    name = str(data.get("name", out.name))
    if single_results(out):  # as 'study run' refuses it: never advise a run that is then refused
        raise ConfigError(f"--out {out}: holds {single_results(out)}, not study '{name}'s; give the --out "
                          f"directory the study was run into")
    groups, tables, missing_ids, stale_ids = _finished_runs(specs)
    if not groups:
        _nothing_to_report(name, specs, out, path_or_name, out_dir, stale_ids)
    rep_dir = _report_dir(out, name)
    draft = rep_dir.parent / f".{rep_dir.name}.draft-{os.getpid()}"
    try:
        shutil.rmtree(draft, ignore_errors=True)
        draft.mkdir()
        answer = _write_report(draft, name, specs, (groups, tables, missing_ids, stale_ids), running_study(out))
        _replace_report(rep_dir, draft)
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM: no half-written draft left beside the report
        shutil.rmtree(draft, ignore_errors=True)
        raise
    except OSError as exc:
        shutil.rmtree(draft, ignore_errors=True)
        where = str(exc.filename or rep_dir).replace(str(draft), str(rep_dir))
        raise ConfigError(f"study '{name}': cannot write the report: {where}: {exc.strerror or exc}; the "
                          f"report in {rep_dir} is left as it was (an earlier one, or none)") from None
    return _moved(answer, draft, rep_dir)


def _nothing_to_report(name: str, specs, out: Path, path_or_name, out_dir, stale_ids: list[str]) -> None:
    """The ConfigError of a report with no run to report (none finished, or only runs made otherwise)."""
    again = f"cistrack study run {path_or_name}" + (f" --out {out_dir}" if out_dir else "")
    if stale_ids:
        raise ConfigError(f"study '{name}': nothing to report: the {len(stale_ids)} finished run(s) in {out / 'runs'} "
                          f"({_ids(stale_ids, 3)}) were made with another scenario, settings, seed or input file "
                          f"than the study now gives them (check --set, --first-seed and --n-seeds: a study "
                          f"directory alone is reported with the values it was run with, 'cistrack study report "
                          f"{out}'), or run them again: {again} --overwrite, with the same --set, --first-seed and --n-seeds")
    raise ConfigError(f"study '{name}': nothing to report: none of its {len(specs)} runs has finished "
                      f"in {out / 'runs'}. Run it first: {again}")


def _replace_report(rep_dir: Path, draft: Path) -> None:
    """The whole new report (written in ``draft``) in place of ``rep_dir``'s: a report is never a
    mixture of two."""
    old = rep_dir.parent / f".{rep_dir.name}.old-{os.getpid()}"
    shutil.rmtree(old, ignore_errors=True)
    rep_dir.rename(old)
    draft.rename(rep_dir)
    shutil.rmtree(old, ignore_errors=True)


def _moved(answer: dict, draft: Path, rep_dir: Path) -> dict:
    """:func:`report_study`'s answer with the draft folder's paths as the report folder's."""
    files = [rep_dir / Path(f).relative_to(draft) for f in answer["files"]]
    return {**answer, "files": files, "text": answer["text"].replace(str(draft), str(rep_dir))}


def _report_dir(out: Path, name: str) -> Path:
    """``out/report``, created; ConfigError naming it when no file can be made there."""
    from cistrack.results.output_paths import make_writable_dir

    rep_dir = out / REPORT_FOLDER
    try:
        make_writable_dir(rep_dir)
    except OSError as exc:
        raise ConfigError(f"study '{name}': cannot write the report to {rep_dir} ({exc.strerror or exc}): the "
                          f"report goes into the study directory's report/ folder; make {out} writable, or copy "
                          "the study directory to a writable place and report the copy") from None
    return rep_dir


def _write_report(rep_dir: Path, name: str, specs, finished: tuple[dict, dict, list[str], list[str]],
                  running: str | None = None) -> dict:
    """Write the report's files into ``rep_dir``; returns :func:`report_study`'s answer (``running``:
    the holder of a study run running in the directory, or None, as :func:`_title` says it)."""
    groups, tables, missing_ids, stale_ids = finished
    study_has_truth = any(x.has_truth for sums in groups.values() for x in sums)
    counted = _COUNTED if study_has_truth else _COUNTED_TRUTHLESS
    arch = architectures_of(specs)
    rows = [_group_row(key, sums, tables[key], arch.get(key[0]), counted) for key, sums in sorted(groups.items())]
    files = [_write_summary_csv(rows, _summary_columns(counted, study_has_truth), rep_dir / "summary.csv"),
             write_runs_csv(groups, rep_dir / "runs.csv")]
    by_filter = write_custody_by_filter(rows, rep_dir / "custody_by_filter.csv")
    files += [by_filter] if by_filter else []
    has_truth = any(r["custody_kept"] is not None for r in rows)
    verdicts = [_verdict_line(r) for r in rows]
    flagged = [flagged_line(f) for f in flagged_runs(groups)]
    title = _title(name, len(specs), missing_ids, stale_ids, running)
    man_rows = _maneuver_rows([sp for sp in specs if sp.run_id not in {*missing_ids, *stale_ids}], groups, tables)
    man_md, man_text, man_files = _maneuver_report(man_rows, rep_dir, name)
    write_text_atomic(rep_dir / "summary.md",
                      _summary_markdown(title, rows, has_truth, counted, arch, verdicts, flagged) + man_md + "\n")
    files.append(rep_dir / "summary.md")
    text = _terminal_text(title, rows, has_truth, counted, verdicts, flagged, rep_dir / "runs.csv") + man_text
    files += _figures(groups, tables, rows, rep_dir, name) + man_files
    return {"text": text, "rows": rows, "files": files, "missing": len(missing_ids), "stale": len(stale_ids),
            "maneuver_rows": man_rows, "study_running": running is not None}
