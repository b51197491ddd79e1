"""Calibration tables of finished studies (issue 16): one row per filter x IOD, then where the
truth became improbable (per pass and per update within a pass).

    python benchmarks/calibration_tables.py STUDY_DIR [STUDY_DIR ...]

Reads each run's manifest.json and steps.parquet under STUDY_DIR/runs, one row per scenario x
filter x IOD. Columns: runs; custody kept with its 95% Wilson interval; runs whose verdict is
tracking (custody kept counts consistent-but-not-converged runs too); final NEES median / 90th percentile; ANEES with its
chi-square(6 M) 95% band; share of runs whose final truth HDR level exceeds 0.99; the
Kolmogorov-Smirnov statistic of the final HDR levels against uniform; runs ending more than
50 km from the truth; the largest final error; runs not finished; the days custody was lost.
The second table gives, for update k of pass p, the median posterior NEES and the share of
runs with HDR level > 0.99 (a consistent filter: about 5.3 and 1% everywhere). The third gives
the median position sigma and error at the end of each pass. The fourth gives the efficiency:
RMS position error across the runs divided by the RMS of the information bound (bound_pos_km) at
the last update of each pass and at the end (1 = the bound; every run counts, lost ones too).
"""
from __future__ import annotations

import glob
import json
import os
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from scipy.stats import binomtest, chi2, kstest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402


def load(study_dir: str) -> dict[tuple[str, str, str], list[tuple[dict, str]]]:
    """(scenario, filter label, IOD) -> [(manifest, run dir)] for the finished runs of one study."""
    out: dict[tuple[str, str, str], list] = {}
    for m in sorted(glob.glob(f"{study_dir}/runs/*/manifest.json")):
        with open(m) as fh:
            man = json.load(fh)
        if "summary" not in man:
            continue
        scen, flt, iod, _seed = man["run_id"].split("__")
        out.setdefault((scen, flt, iod), []).append((man, os.path.dirname(m)))
    return out


def summary_table(groups) -> None:
    print("| scenario | filter | IOD | runs | custody kept (95% CI) | tracking | final NEES median / p90 | "
          "ANEES (chi2 95% band) | final HDR > 0.99 | KS vs uniform | final err > 50 km | max final err km | "
          "not finished | lost days |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (scen, flt, iod), runs in sorted(groups.items()):
        s = [m["summary"] for m, _ in runs]
        n = len(s)
        k = sum(x["custody_kept"] for x in s)
        ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
        nees = np.array([x["final"].get("nees", np.nan) for x in s], float)
        hdr = np.array([x["final"].get("hdr_level", np.nan) for x in s], float)
        err = np.array([x["final"].get("pos_err_km", np.nan) for x in s], float)
        lo, hi = chi2.ppf([0.025, 0.975], 6 * n) / n
        ks = kstest(hdr[np.isfinite(hdr)], "uniform")
        lost = sorted(round(x["custody_lost_t_days"], 2) for x in s
                      if not x["custody_kept"] and x["custody_lost_t_days"] is not None)
        tracking = sum((x.get("verdict") or {}).get("kind") == "tracking" for x in s)
        print(f"| {scen} | {flt} | {iod} | {n} | {k} ({ci.low:.2f}-{ci.high:.2f}) | {tracking} | {np.nanmedian(nees):.1f} / "
              f"{np.nanpercentile(nees, 90):.1f} | {np.nanmean(nees):.3g} ({lo:.2f}-{hi:.2f}) | "
              f"{np.mean(hdr > 0.99):.0%} | {ks.statistic:.2f} (p {ks.pvalue:.2g}) | {int(np.sum(err > 50))} | "
              f"{np.nanmax(err):.1f} | {sum(x['status'] != 'finished' for x in s)} | {lost} |")


_STEP_COLUMNS = ["kind", "nees", "hdr_level", "pass_index", "sigma_pos_km", "pos_err_km", "bound_pos_km"]


def read_step_tables(groups) -> dict[str, dict]:
    """Run directory -> the step-table columns both per-run tables need, each file read once."""
    return {d: pq.read_table(f"{d}/steps.parquet", columns=_STEP_COLUMNS).to_pydict()
            for runs in groups.values() for _, d in runs}


def per_update_table(groups, steps) -> None:
    print("\nPosterior NEES median / share of runs with HDR > 0.99, at update k of each pass:")
    for (scen, flt, iod), runs in sorted(groups.items()):
        acc: dict[tuple[int, int], list] = defaultdict(list)
        for _, d in runs:
            t = steps[d]
            prev, k = None, 0
            for kind, ne, h, p in zip(t["kind"], t["nees"], t["hdr_level"], t["pass_index"]):
                if kind != "update":
                    continue
                k = 0 if p != prev else k + 1
                prev = p
                acc[(int(p), k)].append((ne, h))
        print(f"  {scen} {flt} {iod}:")
        for p in sorted({p for p, _ in acc}):
            cells = []
            for k in range(10):
                v = np.array(acc.get((p, k), []), float)
                if len(v) >= max(5, len(runs) // 5):
                    cells.append(f"{k}: {np.median(v[:, 0]):4.1f}/{np.mean(v[:, 1] > 0.99):4.0%}")
            print(f"    pass {p}: " + "  ".join(cells))


def _pass_ends(runs, steps, a: str, b: str) -> dict[int, list]:
    """Pass number -> [(column a, column b) at the last update of that pass, one pair per run]."""
    acc: dict[int, list] = defaultdict(list)
    for _, d in runs:
        t = steps[d]
        last = {int(p): (x, y) for kind, p, x, y in zip(t["kind"], t["pass_index"], t[a], t[b]) if kind == "update"}
        for p, v in last.items():
            acc[p].append(v)
    return acc


def per_pass_precision_table(groups, steps) -> None:
    print("\nMedian position sigma / position error (km) at the last update of each pass (custody alone "
          "favours wide clouds; this shows what each filter pays for it):")
    for (scen, flt, iod), runs in sorted(groups.items()):
        acc = _pass_ends(runs, steps, "sigma_pos_km", "pos_err_km")
        cells = [f"pass {p}: {np.median([v[0] for v in acc[p]]):.3g} / {np.median([v[1] for v in acc[p]]):.3g}"
                 for p in sorted(acc) if len(acc[p]) >= max(5, len(runs) // 5)]
        print(f"  {scen} {flt} {iod}: " + "  ".join(cells))


def _rms_ratio(pairs) -> tuple[float, float, int]:
    v = np.array([(e, b) for e, b in pairs if np.isfinite(e) and np.isfinite(b) and b > 0], float)
    if v.size == 0:
        return np.nan, np.nan, 0
    rms_b = float(np.sqrt(np.mean(v[:, 1] ** 2)))
    return float(np.sqrt(np.mean(v[:, 0] ** 2))) / rms_b, rms_b, v.shape[0]


def efficiency_table(groups, steps, passes=range(1, 7)) -> None:
    print("\nEfficiency: RMS position error / RMS information bound at the last update of each pass and "
          "at the end (1 = the bound), with the end's RMS bound:")
    print("| scenario | filter | IOD | runs | " + " | ".join(f"pass {p}" for p in passes)
          + " | passes 3-6 pooled | end | RMS bound at end, km |")
    print("|---|---|---|---|" + "---|" * (len(passes) + 3))
    for (scen, flt, iod), runs in sorted(groups.items()):
        acc = _pass_ends(runs, steps, "pos_err_km", "bound_pos_km")
        cells = []
        for p in passes:
            r, _, n = _rms_ratio(acc.get(p, []))
            cells.append(f"{r:.2f}" if n >= max(5, len(runs) // 5) else "-")
        pooled, _, npool = _rms_ratio([v for p in (3, 4, 5, 6) for v in acc.get(p, [])])
        s = [m["summary"]["final"] for m, _ in runs]
        end, bound, _ = _rms_ratio([(f.get("pos_err_km", np.nan), f.get("bound_pos_km", np.nan)) for f in s])
        print(f"| {scen} | {flt} | {iod} | {len(runs)} | " + " | ".join(cells)
              + f" | {pooled:.2f} | {end:.2f} | {bound:.3g} |")


def main(argv=None) -> None:
    dirs = sys.argv[1:] if argv is None else argv
    print("\n".join(machine_lines()))
    groups = {}
    for d in dirs:
        groups.update(load(d))
    summary_table(groups)
    steps = read_step_tables(groups)
    per_update_table(groups, steps)
    per_pass_precision_table(groups, steps)
    efficiency_table(groups, steps)


if __name__ == "__main__":
    main()
