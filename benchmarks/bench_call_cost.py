"""Cost of one ensemble propagate call by span, fresh start against carried step sizes, and the
propagation inside a run of a scenario (not a test).

    .venv/bin/python benchmarks/bench_call_cost.py [--particles 10000] [--repeats 9] [--scenario example-1]

Table 1: 9:2 NRHO ensemble (10 km, 1 cm/s spread), one ``CR3BP().propagate`` call per span, on
all threads: wall and CPU (median of ``--repeats``) with the integrator's initial-step estimate
(no ``steps``) and with the step each particle's previous call proposed (``steps=``, as the PGM
carries them), in microseconds per particle and call. Table 2: every propagate call of one run of
``--scenario`` (seed 1, after a warm-up run): calls, particle-calls and the CPU they take, per
particle-call and per particle-period of the filter's cloud, against the DOP853 compute bound of
about 4 us per particle-period on one core (85 steps x 12 stages x ~150 flops, 16 flops a cycle,
2.45 GHz; issue 31). Particle-periods are counted two ways: nominal (the scenario's particle count
times the run's length in periods, as issue 31 first measured) and integrated (each call's
particles times its span, summed: the work the calls did; the PGM carries more particles than
nominal while it reacquires, up to 4x).
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

import cistrack.propagation.compiled as compiled  # noqa: E402
from cistrack import units  # noqa: E402
from cistrack.plugins.dynamics.cr3bp import CR3BP  # noqa: E402
from cistrack.plugins.dynamics.orbit_catalog import ORBITS  # noqa: E402
from cistrack.runs.pipeline import run_scenario  # noqa: E402
from cistrack.scenario.loading import load_scenario  # noqa: E402

SPANS_H = (0.0, 1 / 60, 0.5, 2.0, 12.0)


def _median_call(dyn, x, span, steps, repeats):
    walls, cpus = [], []
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        dyn.propagate(x, 0.0, span, steps=steps)
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return statistics.median(walls), statistics.median(cpus)


def call_table(n: int, repeats: int) -> None:
    orbit = ORBITS["nrho-9-2"]
    dyn = CR3BP()
    rng = np.random.default_rng(2024)
    x = orbit.state + np.hstack([rng.normal(0.0, 10.0 / units.LU_KM, (n, 3)),
                                 rng.normal(0.0, 1e-5 / units.VU_KMS, (n, 3))])
    dyn.propagate(x, 0.0, 1e-3)  # load the kernels
    print(f"\none propagate call, {n} particles, all threads (us per particle and call, median of {repeats})")
    print(f"{'span':>8} {'fresh wall':>11} {'fresh CPU':>10} {'carried wall':>13} {'carried CPU':>12} {'CPU ratio':>10}")
    for span_h in SPANS_H:
        span = units.hours_to_tu(span_h) if span_h else 1e-12
        steps = dyn.propagate(x, -span, 0.0).steps  # what the previous call over the same span proposed
        fw, fc = _median_call(dyn, x, span, None, repeats)
        cw, cc = _median_call(dyn, x, span, steps, repeats)
        print(f"{span_h:>6.3g} h {fw / n * 1e6:>11.3f} {fc / n * 1e6:>10.3f} {cw / n * 1e6:>13.3f} "
              f"{cc / n * 1e6:>12.3f} {cc / fc:>10.2f}")


def run_table(scenario: str) -> None:
    scen = load_scenario(scenario)
    n_filter = int(scen.components["filter"].params.get("n_particles", 0) or 0)
    periods = scen.duration_days / units.tu_to_days(ORBITS["nrho-9-2"].period)
    period = ORBITS["nrho-9-2"].period
    log: list[tuple[int, float, float, float]] = []
    original = compiled.CompiledDynamics.propagate

    def timed(self, states, t0, times, **kw):
        t, c = time.perf_counter(), time.process_time()
        try:
            return original(self, states, t0, times, **kw)
        finally:
            span = float(np.max(np.abs(np.atleast_1d(np.asarray(times, dtype=float)) - float(t0))))
            log.append((int(np.shape(states)[0]), time.perf_counter() - t, time.process_time() - c,
                        span / period))

    run_scenario(scen, seed=1)
    compiled.CompiledDynamics.propagate = timed
    try:
        t0 = time.perf_counter()
        run_scenario(scen, seed=1)
        total = time.perf_counter() - t0
    finally:
        compiled.CompiledDynamics.propagate = original
    a = np.array(log)
    cloud = a[:, 0] >= min(1000, n_filter)
    pc = a[cloud, 0].sum()
    cpu = a[cloud, 2].sum()
    flown = float(np.sum(a[cloud, 0] * a[cloud, 3]))  # particle-periods the calls integrated
    print(f"\npropagation inside one run of {scenario} (seed 1, {n_filter} particles, {periods:.2f} periods): "
          f"run {total:.2f} s wall")
    print(f"  filter-cloud calls {int(cloud.sum())}, particle-calls {int(pc)} (mean {pc / cloud.sum():.0f} "
          f"particles a call), wall {a[cloud, 1].sum():.3f} s, CPU {cpu:.3f} s ({cpu / pc * 1e6:.3f} us per "
          "particle-call)")
    print(f"  per nominal particle-period ({n_filter} x {periods:.2f}): {cpu / (n_filter * periods) * 1e6:.1f} us, "
          f"{cpu / (n_filter * periods) * 1e6 / 4.0:.1f}x the ~4 us compute bound")
    print(f"  per particle-period integrated (sum of particles x span over the calls: {flown:.0f}): "
          f"{cpu / flown * 1e6:.1f} us, {cpu / flown * 1e6 / 4.0:.1f}x the ~4 us compute bound")
    print(f"  other calls (truth, IOD, bound) {int((~cloud).sum())}: wall {a[~cloud, 1].sum():.3f} s")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--scenario", default="example-1")
    args = ap.parse_args()
    for line in machine_lines():
        print(line)
    call_table(args.particles, args.repeats)
    run_table(args.scenario)
    return 0


if __name__ == "__main__":
    sys.exit(main())
