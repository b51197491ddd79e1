"""Benchmark: start-up of the command line (``cistrack --help``, ``cistrack plugins``, ``import cistrack``).

Run: .venv/bin/python benchmarks/bench_startup.py [--repeat 10] [--baseline OTHER_VENV/bin/cistrack]
Each command runs ``--repeat`` times in a fresh process after one warm-up run (hyperfine's
method: the page cache is warm, so the figures are interpreter and import cost). Prints the
machine, then per command the wall time (mean, standard deviation, min) and the CPU time; with ``--baseline``
the same for another installation (e.g. a checkout before the lean-start change) and the ratio
of the means. Not a test: timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from machine import machine_lines


def _time(cmd: list[str], repeat: int) -> tuple[list[float], list[float]]:
    """Wall times and CPU times (user + system of the child), seconds. On a loaded machine the
    CPU time is the steadier measure of the command's own cost."""
    subprocess.run(cmd, capture_output=True, check=True)  # warm-up
    wall, cpu = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run(cmd, capture_output=True, check=True)
        wall.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
    return wall, cpu


def _commands(cistrack: Path) -> dict[str, list[str]]:
    python = str(cistrack.parent / "python")
    return {
        "cistrack --help": [str(cistrack), "--help"],
        "cistrack plugins": [str(cistrack), "plugins"],
        "python -c 'import cistrack'": [python, "-c", "import cistrack"],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--baseline", type=Path, default=None, help="another installation's cistrack executable")
    args = ap.parse_args()
    here = Path(sys.executable).parent / "cistrack"
    print("\n".join(machine_lines()))
    print(f"repeats: {args.repeat} (after one warm-up run each)")
    rows = []
    for label, cmd in _commands(here).items():
        new = _time(cmd, args.repeat)
        base = _time(_commands(args.baseline)[label], args.repeat) if args.baseline else None
        rows.append((label, new, base))
    head = f"{'command':<30} {'wall mean s':>11} {'sd':>6} {'min':>6} {'cpu mean s':>10}"
    if args.baseline:
        head += f" | {'baseline wall':>13} {'cpu':>6} | {'ratio wall':>10} {'cpu':>5}"
    print(head)
    for label, (wall, cpu), base in rows:
        line = (f"{label:<30} {statistics.mean(wall):11.3f} {statistics.stdev(wall):6.3f} "
                f"{min(wall):6.3f} {statistics.mean(cpu):10.3f}")
        if base:
            bw, bc = base
            line += (f" | {statistics.mean(bw):13.3f} {statistics.mean(bc):6.3f} | "
                     f"{statistics.mean(bw) / statistics.mean(wall):9.1f}x {statistics.mean(bc) / statistics.mean(cpu):4.1f}x")
        print(line)

if __name__ == "__main__":
    main()
