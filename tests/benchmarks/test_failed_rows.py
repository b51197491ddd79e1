"""A benchmark whose child run fails says so in its exit status, not only in a table row."""
from __future__ import annotations

import os
import subprocess
import sys

BENCH = os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks")


def test_bench_memory_exits_non_zero_when_a_case_fails():
    done = subprocess.run([sys.executable, os.path.join(BENCH, "bench_memory.py"), "--sizes", "0", "--cases", "run"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 1
    assert "1 case(s) failed: run 0" in done.stdout


def test_bench_long_file_exits_non_zero_when_a_filter_fails(tmp_path):
    rows = tmp_path / "long.csv"
    subprocess.run([sys.executable, os.path.join(BENCH, "make_long_measurements.py"), "--rows", "200", "--out", str(rows)],
                   check=True, capture_output=True, timeout=300)
    done = subprocess.run([sys.executable, os.path.join(BENCH, "bench_long_file.py"), str(rows), "--rows", "200",
                           "--filters", "pgm", "--pgm-particles", "0"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "1 filter(s) failed: pgm" in done.stdout
