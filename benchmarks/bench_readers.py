"""Reading and writing observation files: measurements per second for each registered reader.

    .venv/bin/python benchmarks/bench_readers.py [--n 20000] [--repeat 3]

Writes ``n`` measurements (two MPC sites, the reader's measurement types) with each reader's
writer and reads them back; prints the best of ``repeat`` times as measurements per second.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack.plugin.registry import load_registry  # noqa: E402
from cistrack.testing.checks_reader import EPOCH, sample_measurements  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    reg = load_registry(autoload_third_party=False)
    print("\n".join(machine_lines()))
    print(f"{a.n} measurements, best of {a.repeat}")
    print(f"{'reader':10} {'type':6} {'write /s':>10} {'read /s':>10} {'bytes/meas':>10}")
    with tempfile.TemporaryDirectory() as d:
        for name in reg.names("reader"):
            reader = reg.create("reader", name)
            for kind in reader.measurement_kinds:
                ms = sample_measurements(kind, n=a.n, seed=1)
                p = Path(d) / f"x{reader.suffixes[0]}"
                tw, tr = [], []
                for _ in range(a.repeat):
                    t0 = time.perf_counter()
                    reader.write(p, ms, EPOCH)
                    tw.append(time.perf_counter() - t0)
                    t0 = time.perf_counter()
                    reader.read(p, EPOCH)
                    tr.append(time.perf_counter() - t0)
                print(f"{name:10} {kind:6} {a.n / min(tw):10.0f} {a.n / min(tr):10.0f} {p.stat().st_size / a.n:10.0f}")


if __name__ == "__main__":
    main()
