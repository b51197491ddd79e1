"""A plugin that ends its import with ``sys.exit``, KeyboardInterrupt or any other BaseException
is listed as a plugin that failed to load, with a warning, and every command still works
(issue 27: ``sys.exit(3)`` on import silenced every command, exit status 3, nothing printed).

The plugin is a real entry point: a distribution's metadata (``*.dist-info`` with
``entry_points.txt``) on ``PYTHONPATH`` of a ``cistrack`` process, so nothing is installed into
the environment the other tests use.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from plugin_site import plugin_site  # tests/ is on sys.path

BODIES = {
    "hostile_exit": "import sys\nsys.exit(3)\n",
    "hostile_interrupt": "raise KeyboardInterrupt\n",
    "hostile_base": "class Odd(BaseException):\n    pass\nraise Odd('odd plugin')\n",
}
EXPECTED = {"hostile_exit": "sys.exit(3)", "hostile_interrupt": "KeyboardInterrupt", "hostile_base": "Odd: odd plugin"}


@pytest.fixture
def site(tmp_path: Path) -> Path:
    """A folder with the distribution ``cistrack-hostile``: one entry point per way of ending an import."""
    return plugin_site(tmp_path / "site", "cistrack-hostile", "1.0", BODIES)


def _cistrack(site: Path, cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *argv], capture_output=True, text=True,
                          env=env, cwd=cwd, timeout=300)


def test_plugins_ending_their_import_abruptly_are_listed_and_the_rest_load(tmp_path, site):
    proc = _cistrack(site, tmp_path, "plugins")
    assert proc.returncode == 0, proc.stderr
    assert "plugins that failed to load:" in proc.stdout
    for module, words in EXPECTED.items():
        listed = [line for line in proc.stdout.splitlines() if f"entry point '{module}'" in line]
        assert len(listed) == 1 and "cistrack-hostile" in listed[0] and words in listed[0], proc.stdout
        assert f"warning: plugin cistrack-hostile: entry point '{module}'" in proc.stderr
    assert "pgm" in proc.stdout and "ukf" in proc.stdout  # the built-ins still load
    assert "Traceback" not in proc.stderr


def test_other_commands_still_speak_beside_them(tmp_path, site):
    proc = _cistrack(site, tmp_path, "scenarios")
    assert proc.returncode == 0 and "quick" in proc.stdout, proc.stderr
    proc = _cistrack(site, tmp_path, "run", "quick", "--quiet", "--set", "seed=-1")  # refused before it runs
    assert proc.returncode == 2 and "cistrack: error:" in proc.stderr and "seed" in proc.stderr, proc.stderr
    assert "sys.exit(3)" in proc.stderr
