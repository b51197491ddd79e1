"""Benchmark: strong scaling over threads and over Dask worker processes (not a test).

    .venv/bin/python benchmarks/bench_scaling.py [--threads 1 2 4 8 16] [--particles 20000]
        [--example1] [--workers 1 2] [--runs 8] [--runs-for-one N] [--study-particles 500] [--repeats 3]

1. Threads: the same ensemble (9:2 NRHO + N(0, 10 km), N(0, 1 cm/s), seed 1) propagated over one
   period with ``CISTRACK_NUM_THREADS`` = 1, 2, 4, ... (default: powers of two up to the cores
   of this machine, and its core count); with ``--example1`` also a whole Example 1 run (seed 1)
   at each thread count. Speedup = time(1 thread) / time(n); efficiency = speedup / n.
2. Dask: a study of ``--runs`` runs (the quick scenario, PGM with ``--study-particles``
   particles, seeds 1..runs, one propagation thread per run) on a local Dask cluster of w worker
   processes for each w of ``--workers``, timed from the first submission to the last result
   (the cluster's start-up excluded). Throughput = runs / time; efficiency = throughput(w) /
   (w x throughput(1)).

Times are wall clock, min over ``--repeats`` (threads) and of one pass (Dask); CPU seconds of
the process are printed beside them, since wall clock on a loaded machine is mostly other load.
On a machine with fewer cores than a row asks for, the row measures oversubscription: read only
rows up to the core count.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

import numpy as np  # noqa: E402

from cistrack import units  # noqa: E402


def _default_threads() -> list[int]:
    cores = os.cpu_count() or 1
    out = [1]
    while out[-1] * 2 <= min(cores, 16):
        out.append(out[-1] * 2)
    if cores <= 16 and cores not in out:
        out.append(cores)
    return out


def _timed(fn, repeats: int) -> tuple[float, float]:
    """(min wall s, CPU s of that call) over ``repeats`` calls."""
    best = (float("inf"), 0.0)
    for _ in range(repeats):
        c, w = time.process_time(), time.perf_counter()
        fn()
        wall, cpu = time.perf_counter() - w, time.process_time() - c
        if wall < best[0]:
            best = (wall, cpu)
    return best


def _table(title: str, unit: str, rows: list[tuple[int, float, float]]) -> None:
    print(title)
    print(f"{unit:>9}{'wall s':>10}{'CPU s':>9}{'speedup':>9}{'efficiency':>12}")
    base = rows[0][1]
    for n, wall, cpu in rows:
        s = base / wall
        print(f"{n:>9}{wall:>10.2f}{cpu:>9.2f}{s:>9.2f}{s / n * rows[0][0]:>12.0%}")
    print()


def thread_scaling(threads: list[int], particles: int, repeats: int, example1: bool) -> None:
    from cistrack.plugins.dynamics.orbit_catalog import ORBITS
    from cistrack.plugins.dynamics.cr3bp import CR3BP

    orbit = ORBITS["nrho-9-2"]
    rng = np.random.default_rng(1)
    sig = np.r_[[units.km_to_lu(10.0)] * 3, [units.kms_to_vu(1e-5)] * 3]
    x = orbit.state + rng.normal(size=(particles, 6)) * sig
    dyn = CR3BP()
    dyn.propagate(x[:100], 0.0, orbit.period)  # compile or load the kernels
    rows = []
    for n in threads:
        os.environ["CISTRACK_NUM_THREADS"] = str(n)
        wall, cpu = _timed(lambda: dyn.propagate(x, 0.0, orbit.period), repeats)
        rows.append((n, wall, cpu))
    _table(f"propagation: {particles} particles over one 9:2 NRHO period ({orbit.period:.4f} TU), "
           f"min of {repeats}", "threads", rows)
    if example1:
        from cistrack.runs.pipeline import run_scenario
        from cistrack.scenario.loading import load_scenario

        scen = load_scenario("example-1")
        run_scenario(scen, seed=1)
        rows = []
        for n in threads:
            os.environ["CISTRACK_NUM_THREADS"] = str(n)
            wall, cpu = _timed(lambda: run_scenario(scen, seed=1), repeats)
            rows.append((n, wall, cpu))
        _table(f"Example 1 run (PGM, 10,000 particles, seed 1), min of {repeats}", "threads", rows)
    os.environ.pop("CISTRACK_NUM_THREADS", None)


STAGES = ("time_initialize_s", "time_predict_s", "time_update_s", "time_metrics_s", "whole_run_s")


def _stage_seconds(run_dir: Path) -> dict[str, float]:
    """Seconds each pipeline stage took in one run (sums over the run's step table)."""
    import pyarrow.parquet as pq

    table = pq.read_table(run_dir / "steps.parquet")
    out = {}
    for col in STAGES:
        if col in table.column_names:
            out[col] = float(np.nansum(table.column(col).to_numpy(zero_copy_only=False).astype(float)))
    manifest = json.loads((run_dir / "manifest.json").read_text())
    out["whole_run_s"] = float(manifest.get("wall_time_s", np.nan))
    return out


def dask_scaling(workers: list[int], runs: int, particles: int, runs_for_one: int | None) -> None:
    """Throughput of a study on a local Dask cluster per worker count, and per pipeline stage the
    mean seconds per run (a stage whose time per run grows with the worker count is contending for
    a shared resource: memory bandwidth, caches, the disk)."""
    from cistrack.studies.study import close_dask_client, execute_run, make_executor, plan_runs

    rows, stages = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for w in workers:
            n_runs = runs_for_one if (w == 1 and runs_for_one) else runs
            study = Path(tmp) / f"scaling{w}.toml"
            study.write_text(f'name = "scaling"\nscenarios = ["quick"]\n'
                             f'filters = [{{ name = "pgm", n_particles = {particles}, n_components = 3 }}]\n'
                             f'iod = [{{ name = "noisy-range", n_particles = {particles} }}]\n'
                             f"seeds = {list(range(1, n_runs + 1))}\n")
            out_dir = Path(tmp) / f"w{w}"
            _, specs, _ = plan_runs(study, out_dir)
            os.environ["CISTRACK_NUM_THREADS"] = "1"  # inherited by the workers: one thread per run
            ex = make_executor(w, dask="local")
            try:
                ex.submit(os.getpid).result()  # a worker is up
                c, t0 = time.process_time(), time.perf_counter()
                futures = [ex.submit(execute_run, s) for s in specs]
                for f in futures:
                    f.result()
                rows.append((w, n_runs, time.perf_counter() - t0, time.process_time() - c))
            finally:
                close_dask_client(ex)
            per_run = [_stage_seconds(d) for d in sorted((out_dir / "runs").iterdir()) if (d / "steps.parquet").exists()]
            stages.append({k: float(np.mean([r.get(k, np.nan) for r in per_run])) for k in STAGES})
    os.environ.pop("CISTRACK_NUM_THREADS", None)
    print(f"Dask study: quick scenario, PGM and noisy-range IOD with {particles} particles, seeds 1..runs, "
          "on a local cluster of w worker processes (one propagation thread each); wall from first "
          "submission to last result; efficiency = throughput(w) / (w x throughput(1))")
    print(f"{'workers':>9}{'runs':>7}{'wall s':>10}{'runs/s':>9}{'speedup':>9}{'efficiency':>12}")
    base = rows[0][1] / rows[0][2] / rows[0][0]  # runs/s per worker at the first row
    for w, n, wall, _cpu in rows:
        thr = n / wall
        print(f"{w:>9}{n:>7}{wall:>10.2f}{thr:>9.2f}{thr / (base * rows[0][0]):>9.2f}{thr / (w * base):>12.0%}")
    print()
    print("per stage: mean seconds per run (efficiency = time per run with the fewest workers / time per run with w)")
    names = [k.removeprefix("time_").removesuffix("_s") for k in STAGES]
    print(f"{'workers':>9}" + "".join(f"{n:>12}" for n in names) + "".join(f"{'eff ' + n[:6]:>13}" for n in names))
    for (w, *_), st in zip(rows, stages):
        print(f"{w:>9}" + "".join(f"{st[k]:>12.4f}" for k in STAGES)
              + "".join(f"{stages[0][k] / st[k]:>13.0%}" if st[k] > 0 else f"{'-':>13}" for k in STAGES))
    print()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, nargs="+", default=_default_threads())
    ap.add_argument("--particles", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--example1", action="store_true", help="also time a whole Example 1 run per thread count")
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--study-particles", type=int, default=500)
    ap.add_argument("--runs-for-one", type=int, default=None,
                    help="runs in the one-worker row (default --runs): the baseline of a large study")
    args = ap.parse_args()
    print("\n".join(machine_lines()))
    print()
    thread_scaling(sorted(args.threads), args.particles, args.repeats, args.example1)
    if args.workers:
        dask_scaling(sorted(args.workers), args.runs, args.study_particles, args.runs_for_one)
    return 0


if __name__ == "__main__":
    sys.exit(main())
