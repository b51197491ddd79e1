"""End-to-end benchmark of the paper's Example 1 (IOD + PGM over one 9:2 NRHO orbit).

Prints the run time of `cistrack run example-1` in-process (wall and CPU, after one warm-up run
that compiles or loads the numba kernels), a per-stage breakdown taken from a separate profiled
run (IOD, propagation, clustering, Kalman update, resampling, metrics, the rest), and the whole
process: ``--processes`` fresh ``cistrack run SCENARIO --seed N --quiet`` processes, exec to exit
(start-up, numba's kernel-cache load, the run, writing the results), and with ``--timeline`` the
split of one such process by stage (``process_timeline.py``).

    .venv/bin/python benchmarks/bench_example1.py [--particles 10000] [--repeat 3] [--processes 3] [--timeline]
    taskset -c 0,1 .venv/bin/python benchmarks/bench_example1.py --repeat 5 --processes 5 --timeline   # 2 cores
"""
from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack.runs.pipeline import run_scenario  # noqa: E402
from cistrack.scenario.loading import load_scenario  # noqa: E402

def _cumtime(stats: pstats.Stats, filename_part: str, func: str) -> float:
    """Cumulative seconds of ``func`` in files whose path contains ``filename_part``: written so that
    it matches both the source layout (core/runs/pipeline.py) and an installed one (cistrack/run.py)."""
    total = 0.0
    for (fname, _line, fn), (_cc, _nc, _tt, ct, _callers) in stats.stats.items():
        if fn == func and filename_part in fname:
            total += ct
    return total


def _called_from(stats: pstats.Stats, func: str, caller_func: str) -> float:
    """Cumulative time of ``func`` (any file) spent in calls made (directly or via one helper)
    from ``caller_func``."""
    total = 0.0
    for (fname, _l, fn), (_cc, _nc, _tt, _ct, callers) in stats.stats.items():
        if fn != func or "plugins/clustering" not in fname:
            continue
        for (cfile, _cl, cfn), (_a, _b, _c, ct) in callers.items():
            if cfn == caller_func:
                total += ct
            elif cfn == "_ensure_clustered":
                inner = stats.stats.get((cfile, _cl, cfn))
                if inner:
                    share = sum(v[3] for (_f, _x, g), v in inner[4].items() if g == caller_func)
                    total += ct * (share / inner[3] if inner[3] > 0 else 0.0)
    return total


def _processes(scenario: str, seed: int, overrides: list[str], n: int) -> list[tuple[float, float]]:
    """Wall and CPU seconds (user + system, all threads) of ``n`` whole ``cistrack run`` processes
    after one warm-up process; the children run without PYTHONDONTWRITEBYTECODE (bytecode as an
    installed package has it)."""
    exe = Path(sys.executable).parent / "cistrack"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "cistrack.cli"]
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    tmp = Path(tempfile.mkdtemp(prefix="cistrack-bench-example1-"))
    out: list[tuple[float, float]] = []
    try:
        for i in range(n + 1):
            shutil.rmtree(tmp / "run", ignore_errors=True)
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            subprocess.run(cmd + ["run", scenario, "--seed", str(seed), "--quiet", "--out", str(tmp / "run")]
                           + overrides, check=True, env=env)
            wall = time.perf_counter() - t
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            if i:  # the first one is the warm-up
                out.append((wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


def _timeline(scenario: str, seed: int, overrides: list[str]) -> None:
    """One fresh process split by stage (benchmarks/process_timeline.py), printed as it prints it."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory(prefix="cistrack-bench-timeline-") as tmp:
        script = Path(__file__).resolve().parent / "process_timeline.py"
        res = subprocess.run([sys.executable, str(script), "run", scenario, "--seed", str(seed), "--quiet",
                              "--out", str(Path(tmp) / "run")] + overrides,
                             capture_output=True, text=True, env=env, check=True)
    print("one process split by stage (process_timeline.py):")
    print(res.stderr.rstrip())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="example-1")
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--processes", type=int, default=3, help="whole cistrack processes to time (0: none)")
    ap.add_argument("--timeline", action="store_true", help="also split one process by stage")
    args = ap.parse_args()
    scen = load_scenario(args.scenario).with_overrides(
        {"filter": {"n_particles": args.particles}, "iod": {"n_particles": args.particles}})
    for line in machine_lines():
        print(line)
    print(f"scenario {scen.name}: filter {scen.components['filter'].name}, IOD {scen.components['iod'].name}, "
          f"{args.particles} particles, {scen.duration_days:g} days, seed {args.seed}")
    t0 = time.perf_counter()
    res = run_scenario(scen, seed=args.seed)
    print(f"warm-up run (includes numba compile or cache load): {time.perf_counter() - t0:.2f} s")
    walls, cpus = [], []
    for _ in range(args.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        res = run_scenario(scen, seed=args.seed)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    s = res.summary
    prof = cProfile.Profile()
    prof.enable()
    run_scenario(scen, seed=args.seed)
    prof.disable()
    st = pstats.Stats(prof)
    total_prof = max(_cumtime(st, "runs/pipeline.py", "_run"), 1e-9)
    stages = {
        "IOD": _cumtime(st, "plugins/iod", "estimate"),
        # the kernels run on worker threads, which cProfile does not see: time the Python call
        # that waits for them (filter predictions and the truth)
        "propagation": _cumtime(st, "propagation/compiled.py", "propagate"),
        "clustering": _cumtime(st, "plugins/clustering", "cluster"),
        "resampling": _cumtime(st, "plugins/filters", "_sample_posterior"),
        "metrics": _cumtime(st, "/metrics.py", "step_metrics"),
    }
    upd = _cumtime(st, "plugins/filters", "update")
    # clustering is triggered from update() or from the belief after a prediction: it has its own
    # line, so subtract the part of it that ran inside update()
    stages["update (Kalman, weights)"] = max(upd - stages["resampling"] - _called_from(st, "cluster", "update"), 0.0)
    other = total_prof - sum(v for k, v in stages.items())
    print()
    print(f"{'stage':<28}{'seconds':>10}{'share':>9}")
    for k, v in stages.items():
        print(f"{k:<28}{v:>10.2f}{v / total_prof:>9.1%}")
    print(f"{'other (truth, hooks, I/O)':<28}{max(other, 0):>10.2f}{max(other, 0) / total_prof:>9.1%}")
    print(f"{'total (profiled run)':<28}{total_prof:>10.2f}")
    print()
    print(f"run time in-process, {args.repeat} runs: wall min {min(walls):.2f} s, median {statistics.median(walls):.2f} s; "
          f"CPU median {statistics.median(cpus):.2f} s")
    default_n = load_scenario(args.scenario).components["filter"].params.get("n_particles")
    overrides = [] if args.particles == default_n else [
        "--set", f"filter.n_particles={args.particles}", "--set", f"iod.n_particles={args.particles}"]
    if args.processes > 0:
        proc = _processes(args.scenario, args.seed, overrides, args.processes)
        pw = [w for w, _ in proc]
        print(f"whole process (cistrack run {args.scenario} --seed {args.seed} --quiet), {len(proc)} runs: "
              f"wall min {min(pw):.2f} s, median {statistics.median(pw):.2f} s; "
              f"CPU median {statistics.median(c for _, c in proc):.2f} s")
        print(f"process - run (start-up, numba kernel-cache load, first calls, writing results): "
              f"{statistics.median(pw) - statistics.median(walls):.2f} s (medians)")
    if args.timeline:
        _timeline(args.scenario, args.seed, overrides)
    f = s.final
    print(f"custody {'kept' if s.custody_kept else 'LOST'}; {s.n_updates} updates over {s.n_passes} passes; "
          f"final sigma pos {f['sigma_x_km']:.2f}/{f['sigma_y_km']:.2f}/{f['sigma_z_km']:.2f} km, "
          f"vel {f['sigma_vx_cms']:.2f}/{f['sigma_vy_cms']:.2f}/{f['sigma_vz_cms']:.2f} cm/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
