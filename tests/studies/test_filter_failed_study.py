"""A study in which a filter raises: its runs end "filter-failed", the study says how many, and
the report leaves them out of the final-state calibration and efficiency (probe N10: the runs'
states before the crash had been scored as a calibrated filter more efficient than a working one,
and ``study run`` had said "0 failed" and nothing else).

A real plugin distribution on PYTHONPATH (a UKF that raises KeyError at its third update), the
real CLI in a subprocess, the quick scenario's first 1.4 days."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from plugin_site import plugin_site  # tests/ is on sys.path

RAISES = '''
from cistrack.api import hookimpl
from cistrack.plugins.filters.ukf import UKFFilter


class RaisesLate(UKFFilter):
    """A UKF that raises KeyError at its third update."""

    def update(self, m):
        self._n = getattr(self, "_n", 0) + 1
        if self._n == 3:
            raise KeyError("nope")
        super().update(m)


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "raises-late", RaisesLate)
'''

STUDY = """
name = "crash"
scenarios = ["quick"]
filters = [{ name = "ukf" }, { name = "raises-late" }]
iod = [{ name = "noisy-range", n_particles = 300 }]
seeds = [1, 2]
[overrides]
duration_days = 1.4
"""


def _cli(site: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=600)


@pytest.fixture(scope="module")
def crashed(tmp_path_factory):
    d = tmp_path_factory.mktemp("crash")
    site = plugin_site(d / "site", "cistrack-raises", "0.1", {"cistrack_raises_plugin": RAISES},
                       {"raises": "cistrack_raises_plugin"})
    (d / "crash.toml").write_text(STUDY)
    ran = _cli(site, d, "study", "run", str(d / "crash.toml"), "--out", str(d / "out"), "--workers", "1", "--quiet")
    assert ran.returncode == 0, ran.stderr
    told = _cli(site, d, "study", "run", str(d / "crash.toml"), "--out", str(d / "again"), "--workers", "1")
    rep = _cli(site, d, "study", "report", str(d / "crash.toml"), "--out", str(d / "out"))
    assert rep.returncode == 0, rep.stderr
    return told.stdout, " ".join(rep.stdout.split())


def test_study_run_says_how_many_completed_runs_ended_with_their_filter_raising(crashed):
    told, _ = crashed
    assert "4 runs completed (2 of them filter-failed: the filter raised; the report lists them)" in told


def test_the_report_gives_a_crashed_filter_no_final_anees_or_hdr_level(crashed):
    _, report = crashed
    assert ("raises-late / noisy-range / quick: custody 0/2 = 0.00 [0.00-0.66]; final ANEES - [---] - (0 runs); "
            "HDR KS D = -, p = - (0 runs)") in report


def test_the_report_gives_a_crashed_filter_no_final_efficiency(crashed):
    _, report = crashed
    assert "- raises-late / noisy-range / quick: - - ukf / noisy-range / quick: final" in report
