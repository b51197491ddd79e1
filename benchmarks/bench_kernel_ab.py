"""Two generated kernel modules of one model, side by side in one process (not a test).

    .venv/bin/python benchmarks/bench_kernel_ab.py A.py B.py [--model ephemeris|cr3bp]
        [--cases tight wide outputs] [--particles 10000] [--rounds 9]

A and B are generated kernel modules (``cistrack_kernel_<rhs>_<digest>.py`` in the kernel cache,
:func:`cistrack.propagation.kernel_cache_dir`), typically the same model's kernel before and
after a change of the generator: build each by running the model once from each checkout (the
two share the cache directory), then compare them here. Both modules' ``propagate_lanes_kernel``
run the same states over one 9:2 NRHO period in this process, alternating A, B, B, A, ..., one
thread, and the table gives each one's CPU microseconds per particle-period (minimum and median
over ``--rounds``), the median of the per-round ratios B/A, and whether the two gave the same
states bit for bit. Measured in one process the ratio is steady to about 1 % on the shared
development machine, where separate processes (``bench_ephemeris.py``) scatter by 5-10 %.

The cases are those of ``bench_ephemeris.py``: ``tight`` (N(0, 10 km) and N(0, 1 cm/s) about the
orbit, one output), ``wide`` (1000 km and 1 m/s, one output), ``outputs`` (tight, 49 outputs).
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from bench_ephemeris import CASES, placed_in_real_frame  # noqa: E402


def load_module(path: str):
    """Import a generated kernel module from its file (its numba cache beside it is reused)."""
    if not os.path.isfile(path):
        raise SystemExit(f"bench_kernel_ab: no kernel module at {path}")
    name = os.path.basename(path)[:-3]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    if not hasattr(module, "propagate_lanes_kernel"):
        raise SystemExit(f"bench_kernel_ab: {path} has no propagate_lanes_kernel (a model without lockstep lanes)")
    return module


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--model", choices=["ephemeris", "cr3bp"], default="ephemeris")
    ap.add_argument("--cases", nargs="+", choices=sorted(CASES), default=["tight", "wide", "outputs"])
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--rounds", type=int, default=9)
    args = ap.parse_args(argv)
    os.environ["CISTRACK_NUM_THREADS"] = "1"

    from machine import machine_lines

    from cistrack import units
    from cistrack.plugins.dynamics.cr3bp import CR3BP
    from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
    from cistrack.plugins.dynamics.orbit_catalog import ORBITS

    mods = {"A": load_module(args.a), "B": load_module(args.b)}
    orbit = ORBITS["nrho-9-2"]
    period = float(orbit.period)
    model = EphemerisDynamics(epoch="2026-01-01T00:00:00Z") if args.model == "ephemeris" else CR3BP()
    if args.model == "ephemeris":
        model._ensure_window(0.0, period)
    params = model._params()
    pos, rad = model._bodies_arrays()
    n = args.particles
    rng = np.random.default_rng(2026)

    def run(mod, y0, times):
        out = np.empty((times.size, n, 6))
        status = np.zeros(n, dtype=np.int64)
        c = time.process_time()
        mod.propagate_lanes_kernel(0, n, y0, params, 0.0, times, model.rtol, model.atol, pos, rad, 100_000,
                                   np.zeros(n), out, np.full(n, -1), np.full(n, np.inf), status)
        return (time.process_time() - c) / n * 1e6, out

    for line in machine_lines():
        print(f"# {line}")
    print(f"# A: {os.path.basename(args.a)} (lanes {mods['A'].LANES})")
    print(f"# B: {os.path.basename(args.b)} (lanes {mods['B'].LANES})")
    print(f"# model {args.model}, {n} particles, one thread, {args.rounds} rounds, CPU us per particle-period")
    print(f"{'case':<9}{'A min':>8}{'A median':>10}{'B min':>8}{'B median':>10}{'B/A':>7}  same numbers")
    for case in args.cases:
        sigma_km, outputs = CASES[case]
        sig = np.r_[[units.km_to_lu(sigma_km)] * 3, [units.kms_to_vu(1e-6 * sigma_km)] * 3]
        x = orbit.state + rng.normal(size=(n, 6)) * sig
        if args.model == "ephemeris":
            x = model.to_inertial(placed_in_real_frame(model, x), 0.0)
        times = np.linspace(0.0, period, outputs + 1)[1:]
        same = np.array_equal(run(mods["A"], x, times)[1], run(mods["B"], x, times)[1])
        cpu = {"A": [], "B": []}
        for r in range(args.rounds):
            for key in ("A", "B") if r % 2 == 0 else ("B", "A"):
                cpu[key].append(run(mods[key], x, times)[0])
        a, b = np.array(cpu["A"]), np.array(cpu["B"])
        print(f"{case:<9}{a.min():>8.2f}{np.median(a):>10.2f}{b.min():>8.2f}{np.median(b):>10.2f}"
              f"{np.median(b / a):>7.3f}  {'yes' if same else 'NO'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
