"""Benchmark: the first run on a machine (empty numba and kernel caches) against a warm run.

Run: .venv/bin/python benchmarks/bench_first_run.py [--repeats 3] [--modes auto 0 1] [--scenario example-1]

Each cold run gets fresh, empty ``NUMBA_CACHE_DIR`` and ``CISTRACK_KERNEL_DIR`` directories
(numba then finds none of its cached functions, cistrack none of its generated kernels: the
state of a fresh install); the warm runs share one pair that a first, uncounted run filled.
Cold and warm runs alternate (cold, warm, cold, warm, ...) so that both see the same background
load. ``--modes`` are values of ``CISTRACK_BACKGROUND_COMPILE`` for the cold runs: ``auto``
(unset: a second process compiles the lockstep kernel when a core is idle), ``0`` (never),
``1`` (always). Prints the machine and load, then per kind of run the wall and CPU seconds
(median and min; CPU is user + system of the process and its children) and the first run's
extra wall time over the warm median. Not a test: timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine import machine_lines


def _once(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(cmd, capture_output=True, check=True, env=env)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _env(caches: Path, mode: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["NUMBA_CACHE_DIR"] = str(caches / "numba")
    env["CISTRACK_KERNEL_DIR"] = str(caches / "kernels")
    env.pop("CISTRACK_BACKGROUND_COMPILE", None)
    if mode != "auto":
        env["CISTRACK_BACKGROUND_COMPILE"] = mode
    return env


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--modes", nargs="+", default=["auto"], choices=["auto", "0", "1"])
    ap.add_argument("--scenario", default="example-1")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args(argv)
    cistrack = Path(sys.executable).parent / "cistrack"
    work = Path(tempfile.mkdtemp(prefix="cistrack-first-run-"))
    os.chmod(work, 0o700)
    try:
        warm = work / "warm"
        warm.mkdir(mode=0o700)

        def cmd(out: Path) -> list[str]:
            return [str(cistrack), "run", args.scenario, "--set", f"seed={args.seed}", "--quiet", "--out", str(out)]

        print(f"# filling the warm caches ({' '.join(cmd(work / 'out'))})", flush=True)
        _once(cmd(work / "out"), _env(warm, "auto"))
        for line in machine_lines():
            print(f"# {line}")
        results: dict[str, list[tuple[float, float]]] = {"warm": []}
        for r in range(args.repeats):
            for mode in args.modes:
                cold = work / f"cold-{mode}-{r}"
                cold.mkdir(mode=0o700)
                results.setdefault(f"cold, background={mode}", []).append(_once(cmd(work / "out"), _env(cold, mode)))
                shutil.rmtree(cold, ignore_errors=True)
                results["warm"].append(_once(cmd(work / "out"), _env(warm, "auto")))
                print(f"#   repeat {r + 1}, mode {mode}: cold {results[f'cold, background={mode}'][-1][0]:.1f} s, "
                      f"warm {results['warm'][-1][0]:.1f} s", flush=True)
        print(f"# load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        warm_median = statistics.median(w for w, _ in results["warm"])
        print(f"{'run':<28}{'n':>3}{'wall median':>13}{'wall min':>10}{'CPU median':>12}{'extra wall':>12}")
        for kind, rows in results.items():
            walls, cpus = [w for w, _ in rows], [c for _, c in rows]
            extra = statistics.median(walls) - warm_median
            print(f"{kind:<28}{len(rows):>3}{statistics.median(walls):>13.1f}{min(walls):>10.1f}"
                  f"{statistics.median(cpus):>12.1f}{extra:>12.1f}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
