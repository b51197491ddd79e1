"""The same scenario and seed give bit-identical step tables however the run is made.

Compared: the CLI and an in-process run, 1 and 2 propagation threads, and (slow) kernels
compiled in the running process against kernels loaded from a warm on-disk cache. Every column
of the step table is compared exactly except the wall-clock timings (``time_*``) and the run id.

The cause these tests guard against: value-changing fast-math flags made the compiled code depend
on whether it was compiled in-process or loaded from numba's cache (see
``cistrack.propagation.dop853_source.DEFAULT_FASTMATH``).
"""
from __future__ import annotations

import inspect
import os
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from cistrack.lazy import LazyJit
from cistrack.propagation import dop853_source
from cistrack.results.store import read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SCENARIO = """
name = "repro"
epoch = "2026-01-01T00:00:00Z"
seed = 3
duration_days = 1.4

[truth]
orbit = "nrho-9-2"

[dynamics]
name = "cr3bp"

[sensor]
name = "ground-telescope"
measure_range = true

[schedule]
name = "paper-example-1"

[iod]
name = "noisy-range"
n_particles = 400

[filter]
name = "pgm"
n_particles = 400
n_components = 3
"""


def _table(directory: Path) -> dict[str, list]:
    t = read_steps(directory)
    return {c: t.column(c).to_pylist() for c in t.column_names if not c.startswith("time_") and c != "run_id"}


def _cli(scenario: Path, out: Path, **env: str) -> dict[str, list]:
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", str(scenario), "--out", str(out), "--quiet"],
                          capture_output=True, text=True, env={**os.environ, **env})
    assert proc.returncode == 0, proc.stderr
    return _table(out)


def _in_process(scenario: Path, out: Path) -> dict[str, list]:
    run_scenario(load_scenario(str(scenario)), output_dir=out)
    return _table(out)


def _assert_identical(a: dict[str, list], b: dict[str, list]) -> None:
    assert a.keys() == b.keys()
    differing = [c for c in a if a[c] != b[c]]
    assert not differing, f"columns differ: {differing}"


@pytest.fixture
def scenario_file(tmp_path) -> Path:
    p = tmp_path / "repro.toml"
    p.write_text(SCENARIO)
    return p


def test_generated_kernels_carry_no_fastmath_flags():
    src = dop853_source.generate_source("from m import f as rhs", 6)
    assert "FASTMATH = False" in src
    assert "fastmath=FASTMATH" in src and "rhs = njit(fastmath=False)(rhs.py_func)" in src


@pytest.mark.parametrize("module", ["cistrack.plugins.dynamics.cr3bp", "cistrack.plugins.dynamics.twobody",
                                   "cistrack.plugins.dynamics.cr3bp_variational", "cistrack.plugins.dynamics.ephemeris_variational",
                                   "cistrack.plugins.clustering.em_numba",
                                   "cistrack.model.mixture_density", "cistrack.astro.ephemeris",
                                   "cistrack.plugins.dynamics.ephemeris_rhs", "cistrack.plugins.dynamics.ephemeris_point_mass_rhs",
                                   "cistrack.plugins.clustering.lloyd",
                                   "cistrack.plugins.clustering.points_and_labels"])
def test_builtin_compiled_functions_carry_no_fastmath_flags(module):
    mod = __import__(module, fromlist=["_"])
    jitted = [v for v in vars(mod).values()
              if isinstance(v, (numba.core.registry.CPUDispatcher, LazyJit)) and inspect.getmodule(v.py_func) is mod]
    assert jitted
    assert [v.__name__ for v in jitted if v.targetoptions.get("fastmath")] == []


def test_cli_and_in_process_with_one_and_two_threads_give_identical_steps(scenario_file, tmp_path):
    one = _cli(scenario_file, tmp_path / "one", CISTRACK_NUM_THREADS="1")
    two = _cli(scenario_file, tmp_path / "two", CISTRACK_NUM_THREADS="2")
    here = _in_process(scenario_file, tmp_path / "here")
    assert len(one["step"]) > 3
    _assert_identical(one, two)
    _assert_identical(one, here)


@pytest.mark.slow
def test_cold_and_warm_kernel_cache_give_identical_steps(scenario_file, tmp_path):
    cache = {"CISTRACK_KERNEL_DIR": str(tmp_path / "kernels"), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    cold = _cli(scenario_file, tmp_path / "cold", CISTRACK_NUM_THREADS="2", **cache)
    warm = _cli(scenario_file, tmp_path / "warm", CISTRACK_NUM_THREADS="1", **cache)
    warm2 = _cli(scenario_file, tmp_path / "warm2", CISTRACK_NUM_THREADS="2", **cache)
    here = _in_process(scenario_file, tmp_path / "here")
    _assert_identical(cold, warm)
    _assert_identical(cold, warm2)
    _assert_identical(cold, here)
