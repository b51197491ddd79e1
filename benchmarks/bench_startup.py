"""Benchmark: start-up of the command line (``cistrack --help``, ``cistrack plugins``, ``import cistrack``).

Run: .venv/bin/python benchmarks/bench_startup.py [--repeat 10] [--baseline OTHER_VENV/bin/cistrack]
Each command runs ``--repeat`` times in a fresh process after one warm-up run (hyperfine's
method: the page cache is warm, so the figures are interpreter and import cost). Prints the
machine, then mean, standard deviation, min and max wall time per command; with ``--baseline``
the same for another installation (e.g. a checkout before the lean-start change) and the ratio
of the means. Not a test: timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

from machine import machine_lines


def _time(cmd: list[str], repeat: int) -> list[float]:
    subprocess.run(cmd, capture_output=True, check=True)  # warm-up
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        subprocess.run(cmd, capture_output=True, check=True)
        out.append(time.perf_counter() - t)
    return out


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
    head = f"{'command':<30} {'mean s':>7} {'sd':>6} {'min':>6} {'max':>6}"
    if args.baseline:
        head += f" | {'baseline mean':>13} {'sd':>6} {'min':>6} | {'ratio':>6}"
    print(head)
    for label, new, base in rows:
        line = (f"{label:<30} {statistics.mean(new):7.3f} {statistics.stdev(new):6.3f} "
                f"{min(new):6.3f} {max(new):6.3f}")
        if base:
            line += (f" | {statistics.mean(base):13.3f} {statistics.stdev(base):6.3f} {min(base):6.3f} | "
                     f"{statistics.mean(base) / statistics.mean(new):5.1f}x")
        print(line)


if __name__ == "__main__":
    main()
