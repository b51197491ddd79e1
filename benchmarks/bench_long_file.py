"""Wall time, rows/s, part files and peak memory of runs on a long measurement file.

Each filter runs in a process of its own (so that its peak RSS is its own) on the first ``--rows``
rows of the file written by ``make_long_measurements.py`` (several sites at common times; rows
sharing a time make one filter step), with results written to a run directory as ``cistrack run``
does. Prints a table with the machine it ran on:

    .venv/bin/python benchmarks/make_long_measurements.py --rows 400000 --out /tmp/long.csv
    .venv/bin/python benchmarks/bench_long_file.py /tmp/long.csv --rows 400000 --filters ukf,enkf

Filters: ukf (defaults), enkf (defaults), pgm (``--pgm-particles``, default 2000, 4 components).
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

SCENARIO = """name = "long-file"
epoch = "2026-01-01T00:00:00Z"
seed = {seed}
duration_days = {days}
[dynamics]
name = "cr3bp"
[sensor]
name = "ground-telescope"
measure_range = true
[iod]
name = "noisy-range"
n_particles = 1000
[filter]
{filter}
[measurements]
file = "{file}"
"""
FILTERS = {"ukf": 'name = "ukf"', "enkf": 'name = "enkf"',
           "pgm": 'name = "pgm"\nn_particles = {n}\nn_components = 4'}


def _prefix(src: Path, rows: int, dst: Path) -> tuple[int, float]:
    """The header and first ``rows`` data rows of ``src``; returns (rows, span in days)."""
    from cistrack.units import parse_utc

    n, first, last = 0, None, None
    with src.open() as fin, dst.open("w") as fout:
        for line in fin:
            if line.startswith("#") or line.startswith("time_utc") or not line.strip():
                fout.write(line)
                continue
            if n >= rows:
                break
            fout.write(line)
            t = line.split(",", 1)[0]
            first = first or t
            last = t
            n += 1
    span = (parse_utc(last) - parse_utc("2026-01-01T00:00:00Z")).total_seconds() / 86400.0
    return n, span


def one(scenario: str, out: str) -> dict:
    """Run one scenario file into ``out``; the figures as a dict (in the child process)."""
    from cistrack.results.store import read_manifest
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    t0 = time.perf_counter()
    res = run_scenario(load_scenario(scenario), output_dir=out)
    wall = time.perf_counter() - t0
    man = read_manifest(out)
    return {"status": res.summary.status, "steps": len(res.rows), "wall_s": wall,
            "prepare_s": res.summary.prepare_time_s, "n_parts": man.get("n_parts"),
            "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", nargs="?")
    ap.add_argument("--rows", type=int, default=400_000)
    ap.add_argument("--filters", default="ukf,enkf,pgm")
    ap.add_argument("--pgm-particles", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--one", nargs=2, metavar=("SCENARIO", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(*args.one)))
        return 0
    if args.file is None:
        ap.error("the measurement file is required (write one with benchmarks/make_long_measurements.py)")
    work = Path(tempfile.mkdtemp(prefix="cistrack-long-"))
    csv = work / "rows.csv"
    rows, days = _prefix(Path(args.file), args.rows, csv)
    for line in machine_lines():
        print(line)
    print(f"file {args.file}: first {rows} rows, {days:.2f} days; seed {args.seed}; results in {work}")
    print(f"{'filter':<16}{'status':<10}{'rows':>8}{'steps':>8}{'wall s':>9}{'rows/s':>9}{'parts':>7}{'peak MiB':>10}")
    failed = []
    for name in args.filters.split(","):
        scen = work / f"{name}.toml"
        filt = FILTERS[name].format(n=args.pgm_particles)
        scen.write_text(SCENARIO.format(seed=args.seed, days=round(days + 0.01, 3), filter=filt, file=csv))
        proc = subprocess.run([sys.executable, __file__, "--one", str(scen), str(work / f"run-{name}")],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            print(f"{name:<16}error: {proc.stderr.strip().splitlines()[-1:]}")
            failed.append(name)
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        label = f"pgm {args.pgm_particles}" if name == "pgm" else name
        print(f"{label:<16}{r['status']:<10}{rows:>8}{r['steps']:>8}{r['wall_s']:>9.1f}{rows / r['wall_s']:>9.0f}"
              f"{r['n_parts']:>7}{r['peak_rss_mib']:>10.0f}", flush=True)
    if failed:  # a table with a lost row is not a measurement: say so in the exit status too
        print(f"{len(failed)} filter(s) failed: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
