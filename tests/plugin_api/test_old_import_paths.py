"""A plugin package written against 0.1's import paths (before core moved into packages) still
installs, passes ``cistrack plugins --check`` and runs by name in a scenario; the old paths cost it
DeprecationWarnings, nothing more."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "tests" / "plugin_packages" / "old_paths"


def _env() -> dict:
    env = dict(os.environ)
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return env


def _cistrack(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-W", "always::DeprecationWarning", "-m", "cistrack.cli", *args],
                          capture_output=True, text=True, env=_env(), timeout=timeout, cwd=ROOT)


@pytest.fixture(scope="module")
def installed():
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    done = subprocess.run([*pip, "install", "--no-deps", "--no-build-isolation", str(PACKAGE)],
                          capture_output=True, text=True, env=_env(), timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    try:
        yield
    finally:
        subprocess.run([*pip, "uninstall", "-y", "cistrack-old-paths-plugin"], capture_output=True, env=_env())


def test_components_load_and_are_listed(installed):
    out = _cistrack("plugins")
    assert out.returncode == 0, out.stderr
    assert "legacy-cr3bp" in out.stdout and "legacy-kmeans" in out.stdout
    assert "failed to load" not in out.stdout


@pytest.mark.parametrize("name", ["legacy-kmeans", "legacy-cr3bp"])
def test_check_passes(installed, name):
    out = _cistrack("plugins", "--check", name)
    assert out.returncode == 0, out.stdout + out.stderr
    assert " 0 failed" in out.stdout


def test_old_paths_warn_with_the_new_ones_named(installed):
    out = _cistrack("plugins", "--check", "legacy-kmeans")
    assert "cistrack.component moved to cistrack.interfaces.component" in out.stdout + out.stderr


def test_a_scenario_runs_with_both_components_by_name(installed, tmp_path):
    out = _cistrack("run", "quick", "--out", str(tmp_path / "run"), "--quiet",
                    "--set", 'dynamics.name="legacy-cr3bp"', "--set", 'filter.clusterer="legacy-kmeans"')
    assert out.returncode in (0, 3), out.stdout + out.stderr  # 3: finished, custody not kept
    manifest = json.loads((tmp_path / "run" / "manifest.json").read_text())
    assert manifest["status"] == "finished"
    assert manifest["components"]["dynamics"]["name"] == "legacy-cr3bp"
    assert manifest["components"]["filter"]["params"]["clusterer"] == "legacy-kmeans"
