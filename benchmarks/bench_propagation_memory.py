"""Memory of ensemble propagation: peak RSS per particle over one 9:2 NRHO period (not a test).

    .venv/bin/python benchmarks/bench_propagation_memory.py [--sizes 100000 1000000]

Each size runs in a fresh child process (Linux: it reads VmRSS/VmHWM from /proc/self/status and
resets the peak through /proc/self/clear_refs): the model is built and its kernels loaded first,
then N particles (9:2 NRHO + N(0, 10 km), N(0, 1 cm/s)) are drawn, the peak is reset and
``CR3BP().propagate(states, 0, period)`` runs once on all threads. Printed per size: the resident
memory before propagating (interpreter, libraries, kernels, and the N input states), the peak
during it, and the bytes per particle of the propagate path = (peak - before) / N + 48 (the input
states, float64 (N, 6)). The last line extrapolates to 10,000,000 particles: before-propagation
memory without the input, plus 10M times the largest bytes per particle measured.

Measured 2026-11-23 (AMD EPYC, 2 logical cores shared with other jobs, load ~22, numba 2 threads,
SIMD-lockstep kernel), ``--sizes 100000 1000000`` and then ``--sizes 10000000``:

             N  before MB   peak MB  propagate bytes/particle
        100000        161       172                       159
       1000000        202       269                       119
      10000000        614      1248                       114
    extrapolated from 1e5: 10,000,000 particles about 1.8 GB; measured: peak RSS 1.25 GB
    (acceptance: 10,000,000 particles over one period fit in 16 GB)

The path holds the input (48 B), the output states (48 B per output time), the impact body, time
and status (24 B) and the alive flags (1 B); the integrator's work arrays are per kernel call on
a chunk of particles (about 12 KB for the 16-lane lockstep kernel), not per particle.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np

from machine import machine_lines


def _status_kb(field: str) -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(f"{field} not in /proc/self/status")


def child(n: int) -> None:
    from cistrack import units
    from cistrack.plugins.dynamics.orbit_catalog import ORBITS
    from cistrack.plugins.dynamics.cr3bp import CR3BP

    orbit = ORBITS["nrho-9-2"]
    dyn = CR3BP()
    dyn.propagate(orbit.state[None], 0.0, 0.01)  # kernels loaded (or compiled) before measuring
    rng = np.random.default_rng(2024)
    sig = np.r_[[units.km_to_lu(10.0)] * 3, [units.kms_to_vu(1e-5)] * 3]
    base_kb = _status_kb("VmRSS")
    states = orbit.state + rng.normal(size=(n, 6)) * sig
    before_kb = _status_kb("VmRSS")
    with open("/proc/self/clear_refs", "w") as fh:  # reset VmHWM to the current RSS
        fh.write("5")
    prop = dyn.propagate(states, 0.0, orbit.period)
    peak_kb = _status_kb("VmHWM")
    assert prop.states.shape == (1, n, 6)
    print(base_kb, before_kb, peak_kb)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    for line in machine_lines():
        print(line)
    print(f"{'N':>10s} {'before MB':>10s} {'peak MB':>9s} {'propagate bytes/particle':>25s}")
    worst, base = 0.0, 0.0
    for n in args.sizes:
        out = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", str(n)],
                             capture_output=True, text=True, check=True).stdout.split()
        base_kb, before_kb, peak_kb = (int(v) for v in out[-3:])
        bpp = (peak_kb - before_kb) * 1024.0 / n + 48.0
        worst, base = max(worst, bpp), base_kb * 1024.0
        print(f"{n:10d} {before_kb / 1024:10.0f} {peak_kb / 1024:9.0f} {bpp:25.0f}")
    total = base + 10_000_000 * worst
    print(f"10,000,000 particles over one period: about {total / 1e9:.1f} GB "
          f"({base / 1e6:.0f} MB process + {worst:.0f} B per particle; acceptance: fits in 16 GB)")


if __name__ == "__main__":
    main()
