"""``cistrack plugins --check NAME`` prints each check's line as soon as the check ends, with its
time when it took over a second, and warns about a check that takes over a minute (the suite is
meant to run in seconds). The slow plugin is a real entry point on a ``cistrack`` process's PYTHONPATH."""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cistrack.cli.main import SLOW_CHECK_S, _print_check
from cistrack.testing.check_results import CheckResult
from plugin_site import plugin_site  # tests/ is on sys.path

SLOW_MODULE = '''
import time
from cistrack.api import hookimpl
from cistrack.plugins.clustering.kmeans import KMeansClusterer

SLEPT = []


class SlowOnce(KMeansClusterer):
    """k-means that sleeps 3 s the first time it clusters."""

    def cluster(self, x, rng):
        if not SLEPT:
            SLEPT.append(1)
            time.sleep(3.0)
        return super().cluster(x, rng)


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "slow-once", SlowOnce)
'''


@pytest.fixture
def site(tmp_path: Path) -> Path:
    return plugin_site(tmp_path / "site", "cistrack-slow", "1.0", {"cistrack_slow_plugin": SLOW_MODULE},
                       {"slow": "cistrack_slow_plugin"})


def _lines_with_times(site: Path, cwd: Path) -> list[tuple[float, str]]:
    """Each stdout line of ``cistrack plugins --check slow-once`` with the seconds since the start at
    which it arrived, and last the time the process ended."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "plugins", "--check", "slow-once"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env, cwd=cwd)
    lines = [(time.monotonic() - t0, line.rstrip("\n")) for line in proc.stdout]
    proc.wait(timeout=300)
    return lines + [(time.monotonic() - t0, f"exit {proc.returncode}")]


def test_each_check_line_comes_when_the_check_ends_not_when_the_suite_does(site, tmp_path):
    lines = _lines_with_times(site, tmp_path)
    assert lines[-1][1] == "exit 0", lines
    first_pass, end = lines[0][0], lines[-1][0]
    assert lines[0][1] == "  PASS  constructs_with_defaults"
    assert end - first_pass > 2.5, lines  # the 3-s check ran after the first line was shown


def test_a_check_over_a_second_shows_its_time(site, tmp_path):
    lines = [text for _, text in _lines_with_times(site, tmp_path)]
    slow = [text for text in lines if " s)" in text]
    assert len(slow) == 1 and slow[0].startswith("  PASS  "), lines
    shown = float(slow[0].rsplit("(", 1)[1].split(" s)")[0])
    assert shown >= 3.0, lines  # the check sleeps 3 s; a loaded machine only adds to it


def test_a_check_over_a_minute_is_warned_about_on_stderr(capsys):
    _print_check(CheckResult("reproducible", True, "", SLOW_CHECK_S + 15.0))
    out, err = capsys.readouterr()
    assert out == f"  PASS  reproducible ({SLOW_CHECK_S + 15.0:.1f} s)\n"
    assert "cistrack: warning: check 'reproducible' took 75 s" in err and "meant to run in seconds" in err
    assert max(map(len, err.splitlines())) <= 120


def test_a_long_failure_is_wrapped_within_120_columns(capsys):
    _print_check(CheckResult("constructs_with_defaults", False, "could not construct it " * 20))
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) > 1 and max(map(len, lines)) <= 120
    assert lines[0].startswith("  FAIL  constructs_with_defaults: could not") and lines[1].startswith(" " * 8)
