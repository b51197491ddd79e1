"""Benchmark: kinematic-fitting IOD, 10,000 particles from 10 measurements (and Gauss).

Run: .venv/bin/python benchmarks/bench_iod.py [--repeat 7]
Prints the machine and a table of wall times (min and median of the repeats) per IOD variant,
with the draws each needed. Not a test: timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
from scipy.integrate import solve_ivp

from cistrack.plugins.iod.gauss import GaussIOD
from cistrack.plugins.iod.kinematic_presets import NoisyRangeIOD, UniformRangeIOD, UniformRangeVelocityBoundIOD
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.units import hours_to_tu

MU = 1.2150582e-2


def _rhs(_t, s):
    x, y, z, vx, vy, vz = s
    r1 = np.sqrt((x + MU) ** 2 + y * y + z * z) ** 3
    r2 = np.sqrt((x - 1 + MU) ** 2 + y * y + z * z) ** 3
    return [vx, vy, vz, x + 2 * vy - (1 - MU) * (x + MU) / r1 - MU * (x - 1 + MU) / r2,
            y - 2 * vx - (1 - MU) * y / r1 - MU * y / r2, -(1 - MU) * z / r1 - MU * z / r2]


def _measurements(sensor):
    """Ten measurements 45 min apart in the first full pass of the approximate 9:2 NRHO."""
    t_end = 2 * 86400.0 / 375149.0
    sol = solve_ivp(_rhs, (0.0, t_end), [1.0221, 0, -0.1821, 0, -0.1033, 0], rtol=1e-11,
                    atol=1e-12, method="DOP853", dense_output=True).sol
    grid = np.arange(0.0, t_end, float(hours_to_tu(1 / 6)))
    first = [p for p in sensor.passes(grid, sol(grid).T) if p.start > 0][0]
    times = first.start + 1e-6 + np.arange(10) * float(hours_to_tu(0.75))
    return sensor.simulate(sol(times).T, times, np.random.default_rng(0))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--particles", type=int, default=10_000)
    args = ap.parse_args()
    sensor = GroundTelescope(measure_range=True)
    ms = _measurements(sensor)
    common = dict(n_particles=args.particles, min_fit=10, max_fit=10)
    methods = {
        "noisy-range": NoisyRangeIOD(**common),
        "uniform-range": UniformRangeIOD(**common),
        "uniform-range-velocity-bound": UniformRangeVelocityBoundIOD(**common),
        "gauss": GaussIOD(**common),
    }
    print(f"machine: {platform.node()} | {platform.machine()} | {platform.processor() or '?'} | "
          f"{os.cpu_count()} cores | Python {platform.python_version()} | numpy {np.__version__}")
    print(f"{args.particles} particles, {len(ms)} measurements in the first pass (10 fitted), "
          f"{args.repeat} repeats")
    print(f"{'method':<30} {'min [s]':>9} {'median [s]':>11} {'draws':>8} {'survival':>9}")
    for name, iod in methods.items():
        times = []
        for r in range(args.repeat):
            rng = np.random.default_rng(r)
            t0 = time.perf_counter()
            cloud = iod.estimate(ms, sensor, rng)
            times.append(time.perf_counter() - t0)
        meta = cloud.meta
        print(f"{name:<30} {min(times):9.3f} {np.median(times):11.3f} {meta['draws']:8d} "
              f"{meta['survival_fraction']:9.2f}")


if __name__ == "__main__":
    main()
