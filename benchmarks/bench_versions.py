"""Two checkouts of cistrack side by side: whole run processes and in-process run time, alternated.

    git worktree add /tmp/old <commit> && make -C /tmp/old .venv/.installed-stamp
    .venv/bin/python benchmarks/bench_versions.py /tmp/old . [--scenario example-1] [--pairs 5] [--runs 5]

Each checkout runs with its own environment (``CHECKOUT/.venv``). Per pair, A then B:
``CHECKOUT/.venv/bin/cistrack run SCENARIO --seed 1 --quiet --out TMP`` (wall, and CPU = user +
system of the process), then the same checkout's Python runs the scenario in-process once to warm
up and ``--runs`` more times (median wall and CPU of those). Alternating A and B lets both see the
same background load on a shared machine; the table gives every pair and the medians, and the
ratios B/A. Prints the machine it ran on. Not a test.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

IN_PROCESS = """
import json, sys, time
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
scen = load_scenario(sys.argv[1])
run_scenario(scen, seed=1)
walls, cpus = [], []
for _ in range(int(sys.argv[2])):
    w, c = time.perf_counter(), time.process_time()
    run_scenario(scen, seed=1)
    walls.append(time.perf_counter() - w)
    cpus.append(time.process_time() - c)
print(json.dumps({"walls": walls, "cpus": cpus}))
"""


def _as_installed() -> dict[str, str]:
    """This environment without ``PYTHONDONTWRITEBYTECODE``: with it, every module edited since its
    .pyc was written is compiled from source in every process (about 0.2 s for an edited checkout),
    which no installed copy does."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _process(checkout: Path, scenario: str) -> tuple[float, float]:
    """Wall and CPU seconds of one ``cistrack run`` process of ``checkout``."""
    out = Path(tempfile.mkdtemp(prefix="cistrack-versions-"))
    try:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run([str(checkout / ".venv/bin/cistrack"), "run", scenario, "--seed", "1", "--quiet",
                        "--out", str(out / "run")], check=True, cwd=checkout, env=_as_installed())
        wall = time.perf_counter() - t
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    finally:
        shutil.rmtree(out, ignore_errors=True)


def _in_process(checkout: Path, scenario: str, runs: int) -> tuple[float, float]:
    """Median wall and CPU seconds of ``runs`` warm in-process runs in ``checkout``'s Python."""
    proc = subprocess.run([str(checkout / ".venv/bin/python"), "-c", IN_PROCESS, scenario, str(runs)],
                          check=True, capture_output=True, text=True, cwd=checkout, env=_as_installed())
    r = json.loads(proc.stdout.strip().splitlines()[-1])
    return statistics.median(r["walls"]), statistics.median(r["cpus"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path, help="checkout A (the reference), with its .venv")
    ap.add_argument("b", type=Path, help="checkout B, with its .venv")
    ap.add_argument("--scenario", default="example-1")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--runs", type=int, default=5, help="warm in-process runs per checkout and pair")
    args = ap.parse_args()
    a, b = args.a.resolve(), args.b.resolve()
    for side in (a, b):
        if not (side / ".venv/bin/cistrack").exists():
            ap.error(f"{side}: no .venv/bin/cistrack (run make .venv/.installed-stamp there)")
    for line in machine_lines():
        print(f"# {line}")
    print(f"# A = {a}\n# B = {b}\n# scenario {args.scenario}, seed 1; {args.pairs} pairs alternating A, B")
    print(f"{'pair':>4} {'A proc wall':>11} {'B proc wall':>11} {'A proc CPU':>10} {'B proc CPU':>10} "
          f"{'A run wall':>10} {'B run wall':>10} {'A run CPU':>9} {'B run CPU':>9}", flush=True)
    rows = []
    for i in range(args.pairs):
        row = []
        for side in (a, b):
            row.append(_process(side, args.scenario))
        for side in (a, b):
            row.append(_in_process(side, args.scenario, args.runs))
        (pa, pb, ra, rb) = row
        rows.append(row)
        print(f"{i + 1:>4} {pa[0]:>11.2f} {pb[0]:>11.2f} {pa[1]:>10.2f} {pb[1]:>10.2f} "
              f"{ra[0]:>10.3f} {rb[0]:>10.3f} {ra[1]:>9.3f} {rb[1]:>9.3f}", flush=True)
    med = [statistics.median(r[k][j] for r in rows) for k in range(4) for j in range(2)]
    print(f"{'med':>4} {med[0]:>11.2f} {med[2]:>11.2f} {med[1]:>10.2f} {med[3]:>10.2f} "
          f"{med[4]:>10.3f} {med[6]:>10.3f} {med[5]:>9.3f} {med[7]:>9.3f}")
    ratios = [statistics.median(r[1][0] / r[0][0] for r in rows), statistics.median(r[3][0] / r[2][0] for r in rows)]
    print(f"# median ratio B/A: process wall {ratios[0]:.2f}, in-process run wall {ratios[1]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
