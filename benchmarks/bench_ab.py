"""Side-by-side wall time of two scenario variants on a busy machine, as ratios.

Runs A and B alternately (A, B, A, B, ...) after one warm-up each, so that both see the same
background load, and prints each pair's B/A ratio and the median ratio. Use it to compare a
change against the previous default, e.g. the PGM's component update:

    .venv/bin/python benchmarks/bench_ab.py example-1 \
        --a '{"filter": {"component_update": "ensemble", "clusterer": "gmm"}}' --b '{}' --pairs 4
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack.runs.pipeline import run_scenario  # noqa: E402
from cistrack.scenario.loading import load_scenario  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--a", default="{}", help="JSON overrides of variant A (the reference)")
    ap.add_argument("--b", default="{}", help="JSON overrides of variant B")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    base = load_scenario(args.scenario)
    scen = {"A": base.with_overrides(json.loads(args.a)), "B": base.with_overrides(json.loads(args.b))}
    for line in machine_lines():
        print(line)
    print(f"scenario {base.name}, seed {args.seed}; A = {args.a}; B = {args.b}")
    for k in scen:  # warm-up (numba compile / cache load)
        run_scenario(scen[k], seed=args.seed)
    print(f"{'pair':>4}{'A s':>9}{'B s':>9}{'B/A':>8}")
    ratios = []
    for i in range(args.pairs):
        t = {}
        for k in ("A", "B") if i % 2 == 0 else ("B", "A"):
            t0 = time.perf_counter()
            run_scenario(scen[k], seed=args.seed)
            t[k] = time.perf_counter() - t0
        ratios.append(t["B"] / t["A"])
        print(f"{i + 1:>4}{t['A']:>9.2f}{t['B']:>9.2f}{ratios[-1]:>8.2f}")
    print(f"median B/A {statistics.median(ratios):.2f} (min {min(ratios):.2f}, max {max(ratios):.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
