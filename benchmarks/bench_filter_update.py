"""Benchmark: one measurement update of each filter at its working size on the 9:2 NRHO.

Run: .venv/bin/python benchmarks/bench_filter_update.py [--repeat 7] [--n 10000]
The belief is a noisy-range IOD cloud propagated to the first OD measurement; each repeat
times update() alone (PGM: clustering + per-component update + resampling from the mixture; no
propagation). Prints min and median wall times. Not a test:
timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import copy
import os
import platform
import time

import numpy as np

from cistrack.plugin.registry import default_registry
from cistrack.runs.pipeline import prepare_run
from cistrack.scenario.loading import load_scenario


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--n", type=int, default=10000)
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    sc = load_scenario("quick").with_overrides({"iod": {"name": "noisy-range", "n_particles": args.n}})
    ctx, _ = prepare_run(sc, seed=1)
    meas = [m for m in ctx.measurements if m.t > ctx.iod_cloud.epoch + 1e-12][0].angles_only()
    reg = default_registry()
    specs = [("pgm", {"n_particles": args.n, "n_components": 6}), ("pgm", {"n_particles": args.n, "n_components": 6, "clusterer": "gmm"}),
             ("enkf", {"n_particles": 1000}), ("ukf", {}), ("sir", {"n_particles": args.n})]
    for name, params in specs:
        f = reg.create("filter", name, **params)
        f.initialize(ctx.iod_cloud, ctx.dynamics, ctx.sensor, np.random.default_rng(0))
        t0 = time.perf_counter()
        f.predict(meas.t)
        t_pred = time.perf_counter() - t0
        times = []
        for r in range(args.repeat):
            g = copy.deepcopy(f)
            t0 = time.perf_counter()
            g.update(meas)
            times.append(time.perf_counter() - t0)
        times = np.array(times) * 1e3
        extra = ", ".join(f"{k}={v}" for k, v in params.items())
        print(f"{name:5s} ({extra}): update min {times.min():7.1f} ms  median {np.median(times):7.1f} ms"
              f"   (predict to first measurement {t_pred:.2f} s)")


if __name__ == "__main__":
    main()
