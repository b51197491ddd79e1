"""Benchmark: strong scaling over threads and over Dask worker processes (not a test).

    .venv/bin/python benchmarks/bench_scaling.py [--threads 1 2 4 8 16] [--particles 20000]
        [--example1] [--workers 1 2] [--runs 8] [--study-particles 500] [--repeats 3]

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
    from cistrack.plugins.dynamics.catalog import ORBITS
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
        from cistrack.run import run_scenario
        from cistrack.scenario import load_scenario

        scen = load_scenario("example-1")
        run_scenario(scen, seed=1)
        rows = []
        for n in threads:
            os.environ["CISTRACK_NUM_THREADS"] = str(n)
            wall, cpu = _timed(lambda: run_scenario(scen, seed=1), repeats)
            rows.append((n, wall, cpu))
        _table(f"Example 1 run (PGM, 10,000 particles, seed 1), min of {repeats}", "threads", rows)
    os.environ.pop("CISTRACK_NUM_THREADS", None)


def dask_scaling(workers: list[int], runs: int, particles: int) -> None:
    from cistrack.study import close_dask_client, execute_run, make_executor, plan_runs

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "scaling.toml"
        study.write_text(f'name = "scaling"\nscenarios = ["quick"]\n'
                         f'filters = [{{ name = "pgm", n_particles = {particles}, n_components = 3 }}]\n'
                         f'iod = [{{ name = "noisy-range", n_particles = {particles} }}]\n'
                         f"seeds = {list(range(1, runs + 1))}\n")
        for w in workers:
            _, specs, _ = plan_runs(study, Path(tmp) / f"w{w}")
            os.environ["CISTRACK_NUM_THREADS"] = "1"  # inherited by the workers: one thread per run
            ex = make_executor(w, dask="local")
            try:
                ex.submit(os.getpid).result()  # a worker is up
                c, t0 = time.process_time(), time.perf_counter()
                futures = [ex.submit(execute_run, s) for s in specs]
                for f in futures:
                    f.result()
                rows.append((w, time.perf_counter() - t0, time.process_time() - c))
            finally:
                close_dask_client(ex)
    os.environ.pop("CISTRACK_NUM_THREADS", None)
    print(f"Dask study: {runs} runs (quick scenario, PGM and noisy-range IOD with {particles} particles, "
          "seeds 1..runs) on a local cluster; CPU s = the client process only")
    print(f"{'workers':>9}{'wall s':>10}{'runs/s':>9}{'speedup':>9}{'efficiency':>12}")
    base = rows[0][1] * rows[0][0]
    for w, wall, _cpu in rows:
        s = rows[0][1] / wall
        print(f"{w:>9}{wall:>10.2f}{runs / wall:>9.2f}{s:>9.2f}{(base / wall) / w:>12.0%}")
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
    args = ap.parse_args()
    print("\n".join(machine_lines()))
    print()
    thread_scaling(sorted(args.threads), args.particles, args.repeats, args.example1)
    if args.workers:
        dask_scaling(sorted(args.workers), args.runs, args.study_particles)
    return 0


if __name__ == "__main__":
    sys.exit(main())
