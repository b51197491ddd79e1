"""Benchmark: whole processes of the command line, from exec to exit: ``cistrack --help``,
``cistrack plugins``, ``import cistrack`` and ``cistrack run example-1 --seed 1 --quiet`` (the
default scenario of ``make demo``; process time includes start-up, numba's kernel-cache load,
the run and writing the results).

Run: .venv/bin/python benchmarks/bench_startup.py [--repeat 10] [--run-repeat 5] [--baseline OTHER_VENV/bin/cistrack]
     taskset -c 0,1 .venv/bin/python benchmarks/bench_startup.py      # as on 2 cores

Each command runs once as a warm-up (page cache, Python bytecode, numba's kernel cache: the
figures are those of a warm install), then ``--repeat`` times (``--run-repeat`` for the run) in
a fresh process. With ``--baseline`` (another installation's ``cistrack``, e.g. a checkout
before a change) the two run alternately, A B A B ..., so that both see the same background
load, and the table adds the ratio of the medians. Prints the machine, then per command the
wall time (median, mean, min) and the CPU time (user + system of the child, all its threads:
the steadier measure on a loaded machine; median and range). The children run without
``PYTHONDONTWRITEBYTECODE`` so that the warm-up leaves bytecode as an installed package has.
Not a test: timings depend on the machine and its load.
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


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _once(cmd: list[str], out: Path | None) -> tuple[float, float]:
    """Wall and CPU seconds (user + system of the child) of one process."""
    if out is not None:
        shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(cmd, capture_output=True, check=True, env=_child_env())
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _commands(cistrack: Path, out: Path) -> dict[str, tuple[list[str], Path | None]]:
    python = str(cistrack.parent / "python")
    return {
        "cistrack --help": ([str(cistrack), "--help"], None),
        "cistrack plugins": ([str(cistrack), "plugins"], None),
        "python -c 'import cistrack'": ([python, "-c", "import cistrack"], None),
        "cistrack run example-1 --quiet": ([str(cistrack), "run", "example-1", "--seed", "1", "--quiet",
                                            "--out", str(out)], out),
    }


def _fmt(samples: list[tuple[float, float]]) -> str:
    wall = [w for w, _ in samples]
    cpu = [c for _, c in samples]
    return (f"{statistics.median(wall):8.3f} {statistics.mean(wall):7.3f} {min(wall):7.3f} "
            f"{statistics.median(cpu):8.3f} {f'{min(cpu):.2f}-{max(cpu):.2f}':>9}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=10, help="runs of each start-up command")
    ap.add_argument("--run-repeat", type=int, default=5, help="runs of the Example 1 process")
    ap.add_argument("--baseline", type=Path, default=None, help="another installation's cistrack executable")
    ap.add_argument("--only-run", action="store_true", help="time only the Example 1 process")
    args = ap.parse_args()
    here = Path(sys.executable).parent / "cistrack"
    print("\n".join(machine_lines()))
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        print("note: PYTHONDONTWRITEBYTECODE is set here; the children run without it")
    print(f"repeats: {args.repeat} per start-up command, {args.run_repeat} of the run (after one warm-up each)"
          + (", alternating with the baseline" if args.baseline else ""))
    tmp = Path(tempfile.mkdtemp(prefix="cistrack-bench-startup-"))
    try:
        new = _commands(here, tmp / "new")
        base = _commands(args.baseline, tmp / "base") if args.baseline else None
        head = f"{'command':<32} {'wall med':>8} {'mean':>7} {'min':>7} {'cpu med':>8} {'cpu range':>9}"
        if base:
            head += (f" | {'base wall':>8} {'mean':>7} {'min':>7} {'cpu med':>8} {'cpu range':>9} | "
                     f"{'ratio wall':>10} {'cpu':>5}")
        print(head)
        for label in new:
            if args.only_run and not label.startswith("cistrack run"):
                continue
            n = args.run_repeat if label.startswith("cistrack run") else args.repeat
            _once(*new[label])
            if base:
                _once(*base[label])
            got: list = []
            got_base: list = []
            for _ in range(n):
                got.append(_once(*new[label]))
                if base:
                    got_base.append(_once(*base[label]))
            line = f"{label:<32} {_fmt(got)}"
            if base:
                ratio_w = statistics.median(w for w, _ in got_base) / statistics.median(w for w, _ in got)
                ratio_c = statistics.median(c for _, c in got_base) / statistics.median(c for _, c in got)
                line += f" | {_fmt(got_base)} | {ratio_w:9.2f}x {ratio_c:4.2f}x"
            print(line, flush=True)
        print("(seconds; ratio = baseline / this installation: above 1 means this one is faster)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
