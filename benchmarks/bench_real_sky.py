"""Benchmark: cost of the measurement function h(x) of the real-sky sensor vs the paper's model.

Run: .venv/bin/python benchmarks/bench_real_sky.py [--repeat 7] [--n 10000] [--seed 0]
Times sensor.measure() on N synodic particles near lunar distance at one time (what a filter
update calls), for 'ground-telescope' (equatorial, geometric az/el) and 'real-telescope' (azel
with light time, aberration, refraction; radec with light time), with the observer state cached
(repeated time) and uncached (a new time each call). Also one call with N distinct times.
Prints the machine, then min and median wall times. Not a test: timings depend on the machine.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.plugins.sensors.real_telescope import RealTelescope

sys.path.insert(0, str(Path(__file__).parent))
from machine import machine_lines  # noqa: E402


def _particles(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.empty((n, 6))
    x[:, :3] = np.array([1.0221, 0.0, -0.1821]) + 0.01 * rng.standard_normal((n, 3))
    x[:, 3:] = np.array([0.0, -0.1033, 0.0]) + 0.01 * rng.standard_normal((n, 3))
    return x


def _time(fn, repeat: int) -> tuple[float, float]:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out), float(np.median(out))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    for line in machine_lines():
        print(line)
    x = _particles(args.n, args.seed)
    sensors = [("ground-telescope (paper, equatorial)", GroundTelescope()),
               ("real-telescope azel (all corrections)", RealTelescope(refraction=True)),
               ("real-telescope radec (light time)", RealTelescope(measurement="radec"))]
    print(f"\nh(x) on {args.n} particles, {args.repeat} repeats, seconds (min / median)")
    print(f"{'sensor':42s} {'same t':>17s} {'new t each call':>17s} {'N distinct t':>14s}")
    for name, s in sensors:
        s.measure(x[:10], 0.2)
        same = _time(lambda: s.measure(x, 0.2), args.repeat)
        counter = iter(np.linspace(0.3, 0.9, 10 * args.repeat))
        new = _time(lambda: s.measure(x, next(counter)), args.repeat)
        tt = 0.2 + np.linspace(0.0, 1e-3, args.n)
        t0 = time.perf_counter()
        s.measure(x, tt)
        distinct = time.perf_counter() - t0
        print(f"{name:42s} {same[0]:8.4f}/{same[1]:8.4f} {new[0]:8.4f}/{new[1]:8.4f} {distinct:14.3f}")


if __name__ == "__main__":
    main()
