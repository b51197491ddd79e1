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

A second table prices dense output on the one-particle kernel (the only one that has it, for
``dense_trajectory``), for ``--dense-particles`` particles: the kernel to the period's end, to the
largest K of ``--outputs`` by shortened steps, and the dense kernel to the end (three more stages
and the 7th-order interpolant's coefficients at every step, which is what ~100 outputs in ~85
steps would need: nearly every step passes an output).
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


def dense_table(dyn, x: np.ndarray, period: float, k: int, repeats: int) -> None:
    """CPU us per particle-period of the one-particle kernel with 1 and ``k`` outputs, and of the
    dense kernel over the period (kernels called directly, one range or one particle a call)."""
    from cistrack.propagation.dop853_dense_source import CTL_SIZE
    from cistrack.propagation.dop853_tableau import INTERPOLATOR_POWER

    mod, params, (pos, rad) = dyn._kernels(), dyn._params(), dyn._bodies_arrays()
    rtol, atol, n = float(dyn.rtol), float(dyn.atol), x.shape[0]

    def shortened(m: int) -> None:
        times = np.linspace(0.0, period, m + 1)[1:]
        mod.propagate_kernel(0, n, x, params, 0.0, times, rtol, atol, pos, rad, 100_000, np.zeros(n),
                             np.empty((m, n, x.shape[1])), np.full(n, -1, dtype=np.int64), np.full(n, np.inf),
                             np.zeros(n, dtype=np.int64))

    rec = (np.empty(256), np.empty(256), np.empty((256, x.shape[1])),
           np.empty((256, INTERPOLATOR_POWER, x.shape[1])))

    def dense() -> None:
        for i in range(n):
            ctl = np.zeros(CTL_SIZE)
            mod.dense_kernel(x[i].copy(), params, period, rtol, atol, pos, rad, 100_000, *rec, ctl)

    ways = {"1 output, shortened steps": lambda: shortened(1), f"{k} outputs, shortened steps": lambda: shortened(k),
            "dense output at every step": dense}
    cpu: dict = {}
    for f in ways.values():
        f()
    for _ in range(repeats):
        for name, f in ways.items():
            c = time.process_time()
            f()
            cpu.setdefault(name, []).append((time.process_time() - c) / n * 1e6)
    base = statistics.median(cpu["1 output, shortened steps"])
    print(f"\none-particle kernel, {n} particles, one period, CPU us per particle-period, median of {repeats}")
    print(f"{'':<30}{'us':>8}{'x 1 output':>12}")
    for name in ways:
        v = statistics.median(cpu[name])
        print(f"{name:<30}{v:>8.2f}{v / base:>12.2f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--outputs", type=int, nargs="+", default=[1, 13, 101])
    ap.add_argument("--dense-particles", type=int, default=1000)
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
    if args.dense_particles > 0:
        dense_table(dyn, x[:args.dense_particles], period, max(args.outputs), args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
