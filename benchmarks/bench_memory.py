"""Benchmark: peak memory per particle of the IOD, one filter step and a whole one-period run.

Each case runs in a fresh process on the paper's Example 1 (uniform-range IOD, 9:2 NRHO, one
period): the process first builds everything once with a small particle count (imports, compiled
kernels, truth), then resets its peak-RSS mark (Linux ``/proc/self/clear_refs``) and runs the case
with N particles. The table gives the peak resident memory above the process's resident memory
before the case, per particle, and the extrapolation to 10,000,000 particles from the growth
between the two largest sizes (peak(N) = base + slope N). The children run with a fixed glibc
mmap threshold (64 KiB) so that freed arrays leave the resident set instead of staying in the heap.

    .venv/bin/python benchmarks/bench_memory.py [--sizes 100000 1000000] [--cases iod pgm-step enkf-step run]

Cases: ``iod`` (kinematic fit, 5x oversampling), ``pgm-step`` / ``enkf-step`` (initialise from the
IOD cloud, predict to the first measurement, update, read the belief and its metrics), ``run``
(IOD and PGM over one period, as ``cistrack run example-1 --set filter.n_particles=N
--set iod.n_particles=N``). Not a test: figures depend on the machine and the libraries.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

CASES = ("iod", "pgm-step", "enkf-step", "run")


def _rss_bytes() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * resource.getpagesize()


def _reset_peak() -> bool:
    """Reset the kernel's peak-RSS mark to the current RSS (Linux >= 4.0); False if not allowed."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def _peak_bytes() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _child(case: str, n: int, seed: int) -> dict:
    from cistrack.evaluation.metrics import step_metrics
    from cistrack.plugin.registry import default_registry
    from cistrack.runs.pipeline import prepare_run, run_scenario
    from cistrack.scenario.loading import load_scenario

    reg = default_registry()
    filt = "enkf" if case == "enkf-step" else "pgm"
    base = load_scenario("example-1").with_overrides({"filter": {"name": filt}})
    small = base.with_overrides({"filter": {"n_particles": 2000}, "iod": {"n_particles": 2000}})
    big = base.with_overrides({"filter": {"n_particles": n}, "iod": {"n_particles": n}})
    if case == "run":
        run_scenario(small, seed=seed)  # warm-up: imports, kernels
        before = _rss_bytes()
        exact = _reset_peak()
        t0 = time.perf_counter()
        run_scenario(big, seed=seed)
    else:
        ctx, rngs = prepare_run(small, seed=seed, registry=reg)
        step = ctx.filter  # warm-up of the filter's code paths on 2,000 particles
        step.initialize(ctx.iod_cloud, ctx.dynamics, ctx.sensor, rngs["filter"])
        t_meas = [t for t in ctx.measurements.times if t > ctx.iod_cloud.epoch + 1e-12][0]
        step.predict(t_meas)
        iod = big.build("iod", reg)
        cloud = None
        if case != "iod":
            cloud = iod.estimate(ctx.measurements, ctx.sensor, rngs["iod"])
        before = _rss_bytes()
        exact = _reset_peak()
        t0 = time.perf_counter()
        if case == "iod":
            cloud = iod.estimate(ctx.measurements, ctx.sensor, rngs["iod"])
        else:
            f = big.build("filter", reg)
            f.initialize(cloud, ctx.dynamics, ctx.sensor, rngs["filter"])
            del cloud
            f.predict(t_meas)
            i = int(list(ctx.measurements.times).index(t_meas))
            m = ctx.measurements[i]
            f.update(m.angles_only() if "range" in m.names else m)
            step_metrics(f.belief, ctx.truth_at(t_meas))
    seconds = time.perf_counter() - t0
    return {"case": case, "n": n, "before": before, "peak": _peak_bytes(), "exact_peak": exact,
            "seconds": seconds}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--child", nargs=2, metavar=("CASE", "N"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(_child(args.child[0], int(args.child[1]), args.seed)))
        return 0
    print("\n".join(machine_lines()))
    print(f"scenario example-1 (uniform-range IOD, one 9:2 NRHO period), seed {args.seed}; "
          "peak RSS above the RSS before the case")
    print(f"{'case':<10}{'particles':>11}{'before MiB':>12}{'peak MiB':>10}{'above MiB':>11}"
          f"{'bytes/particle':>16}{'seconds':>9}")
    results: dict[str, list[dict]] = {}
    failed = []
    # glibc raises its mmap threshold after each freed large block (up to 32 MB), keeping freed
    # arrays in the heap: the RSS before a case would then include memory the case reuses. A fixed
    # threshold returns every array above 64 KiB to the system when it is freed.
    env = dict(os.environ, MALLOC_MMAP_THRESHOLD_="65536", MALLOC_TRIM_THRESHOLD_="65536")
    for case in args.cases:
        for n in sorted(args.sizes):
            out = subprocess.run([sys.executable, __file__, "--seed", str(args.seed), "--child", case, str(n)],
                                 capture_output=True, text=True, env=env)
            if out.returncode != 0:
                print(f"{case:<10}{n:>11}  failed: {out.stderr.strip().splitlines()[-1:]}")
                failed.append(f"{case} {n}")
                continue
            r = json.loads(out.stdout.strip().splitlines()[-1])
            results.setdefault(case, []).append(r)
            above = r["peak"] - r["before"]
            print(f"{case:<10}{n:>11}{r['before'] / 2**20:>12.0f}{r['peak'] / 2**20:>10.0f}{above / 2**20:>11.0f}"
                  f"{above / n:>16.0f}{r['seconds']:>9.1f}" + ("" if r["exact_peak"] else "  (peak since start)"))
    print()
    for case, rs in results.items():
        if len(rs) < 2:
            continue
        a, b = rs[-2], rs[-1]
        slope = ((b["peak"] - b["before"]) - (a["peak"] - a["before"])) / (b["n"] - a["n"])
        at = b["peak"] + slope * (10_000_000 - b["n"])
        print(f"{case}: {slope:.0f} bytes per extra particle ({a['n']} -> {b['n']}); "
              f"10,000,000 particles: peak about {at / 1e9:.1f} GB ({at / 2**30:.1f} GiB)")
    if failed:  # a lost row is not a measurement: say so in the exit status too
        print(f"{len(failed)} case(s) failed: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
