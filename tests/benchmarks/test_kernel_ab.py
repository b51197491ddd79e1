"""bench_kernel_ab refuses what is not a lockstep kernel module, naming the file."""
from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks"))

from bench_kernel_ab import load_module  # noqa: E402


def test_a_missing_kernel_file_is_named_in_the_error(tmp_path):
    path = str(tmp_path / "cistrack_kernel_nothing.py")
    with pytest.raises(SystemExit, match="no kernel module at .*cistrack_kernel_nothing.py"):
        load_module(path)


def test_a_module_without_a_lockstep_kernel_is_refused_by_name(tmp_path):
    path = tmp_path / "cistrack_kernel_plain.py"
    path.write_text("LANES = 16\n")
    with pytest.raises(SystemExit, match="cistrack_kernel_plain.py has no propagate_lanes_kernel"):
        load_module(str(path))
