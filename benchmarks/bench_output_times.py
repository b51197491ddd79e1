"""What landing on output times costs the propagation: one 9:2 NRHO period of a particle cloud
with K output times, in one call or in K calls with carried step sizes (not a test).

    CISTRACK_NUM_THREADS=1 .venv/bin/python benchmarks/bench_output_times.py [--particles 10000] [--repeats 5]

The integrator lands on every output time with a shortened step (no dense output), so each output
costs about one extra step whatever the calls. For each K of ``--outputs`` (evenly spaced over one
period, the last at the period's end) it times, alternating within each round of repeats:

- one call to the K times;
- K calls, each from the previous output with the step sizes the previous call proposed (as the
  PGM's predictions run between its updates);

and prints CPU microseconds per particle-period (medians) beside the one-output call, and whether
the two ways give the same final states bit for bit. Example 1 makes about 100 filter
propagations per period (``bench_call_cost.py``, table 2).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack import units  # noqa: E402
from cistrack.plugins.dynamics.cr3bp import CR3BP  # noqa: E402
from cistrack.plugins.dynamics.orbit_catalog import ORBITS  # noqa: E402


def cloud(n: int) -> np.ndarray:
    """(n, 6) particles about the 9:2 NRHO's catalogue state: 10 km and 1 cm/s per axis."""
    rng = np.random.default_rng(2024)
    return ORBITS["nrho-9-2"].state + np.hstack([rng.normal(0.0, 10.0 / units.LU_KM, (n, 3)),
                                                 rng.normal(0.0, 1e-5 / units.VU_KMS, (n, 3))])


def one_call(dyn, x: np.ndarray, times: np.ndarray) -> np.ndarray:
    return dyn.propagate(x, 0.0, times).states[-1]


def carried_calls(dyn, x: np.ndarray, times: np.ndarray) -> np.ndarray:
    y, t0, steps = x, 0.0, None
    for t in times:
        r = dyn.propagate(y, t0, t, steps=steps)
        y, t0, steps = r.states[-1], float(t), r.steps
    return y


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--outputs", type=int, nargs="+", default=[1, 13, 101])
    args = ap.parse_args()
    for line in machine_lines():
        print(line)
    dyn = CR3BP()
    period = float(ORBITS["nrho-9-2"].period)
    x = cloud(args.particles)
    dyn.propagate(x, 0.0, 1e-3)  # load the kernels
    ways = {"one call": one_call, "carried calls": carried_calls}
    cpu: dict = {}
    final: dict = {}
    for _ in range(args.repeats):
        for k in args.outputs:
            times = np.linspace(0.0, period, k + 1)[1:]
            for name, way in ways.items():
                if k == 1 and name == "carried calls":
                    continue
                c = time.process_time()
                final[k, name] = way(dyn, x, times)
                cpu.setdefault((k, name), []).append((time.process_time() - c) / args.particles * 1e6)
    base = statistics.median(cpu[1, "one call"])
    print(f"\n{args.particles} particles, one 9:2 NRHO period ({period:.4f} TU), CPU us per particle-period, "
          f"median of {args.repeats}")
    print(f"{'outputs':>8} {'one call':>10} {'x 1 output':>11} {'carried calls':>14} {'x 1 output':>11} {'same states':>12}")
    for k in args.outputs:
        one = statistics.median(cpu[k, "one call"])
        row = f"{k:>8} {one:>10.2f} {one / base:>11.2f}"
        if k > 1:
            car = statistics.median(cpu[k, "carried calls"])
            same = bool(np.array_equal(final[k, "one call"], final[k, "carried calls"]))
            row += f" {car:>14.2f} {car / base:>11.2f} {str(same):>12}"
        print(row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
