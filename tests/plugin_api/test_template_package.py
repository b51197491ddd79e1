"""The example plugin package installs with pip, its components appear in `cistrack plugins`
under their names, pass `cistrack plugins --check`, and a scenario uses them by name.

The package is installed (editable, into the running interpreter's environment) for this module
only and uninstalled afterwards.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TEMPLATE = ROOT / "examples" / "plugin-template"
SCENARIO = Path(__file__).with_name("template_scenario.toml")
NAMES = {"dynamics": "template-cr3bp-srp", "clustering": "template-bisecting", "iod": "template-two-point"}


def _env() -> dict:
    env = dict(os.environ)
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return env


def _cistrack(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True,
                          env=_env(), timeout=timeout, cwd=ROOT)


def _pip(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True, env=_env(),
                          timeout=300)


@pytest.fixture(scope="module")
def installed_template():
    done = _pip("install", "--no-deps", "--no-build-isolation", "-e", str(TEMPLATE))
    assert done.returncode == 0, f"pip install -e {TEMPLATE} failed:\n{done.stdout}\n{done.stderr}"
    try:
        yield TEMPLATE
    finally:
        _pip("uninstall", "-y", "cistrack-template")


def test_installed_components_are_listed_by_name_with_their_distribution(installed_template):
    out = _cistrack("plugins")
    assert out.returncode == 0, out.stderr
    for name in NAMES.values():
        line = next((ln for ln in out.stdout.splitlines() if ln.split()[:1] == [name]), "")
        assert "cistrack-template" in line, f"{name} not listed:\n{out.stdout}"
    assert "failed to load" not in out.stdout


@pytest.mark.slow
def test_cli_check_of_an_installed_component_passes(installed_template):
    out = _cistrack("plugins", "--check", NAMES["clustering"])
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 failed" in out.stdout


@pytest.mark.slow
def test_a_scenario_runs_with_the_installed_components_by_name(installed_template, tmp_path):
    out = _cistrack("run", str(SCENARIO), "--out", str(tmp_path / "run"), "--quiet")
    assert out.returncode in (0, 3), out.stdout + out.stderr  # 3: finished but custody lost
    manifest = json.loads((tmp_path / "run" / "manifest.json").read_text())
    assert manifest["status"] == "finished"
    comps = manifest["components"]
    assert comps["dynamics"]["name"] == NAMES["dynamics"]
    assert comps["iod"]["name"] == NAMES["iod"]
    assert comps["filter"]["params"]["clusterer"] == NAMES["clustering"]
    assert manifest["summary"]["n_updates"] > 0


@pytest.mark.slow
def test_the_template_own_test_suite_passes_once_installed(installed_template):
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(TEMPLATE / "tests")],
                         capture_output=True, text=True, env=_env(), timeout=600, cwd=TEMPLATE)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert "skipped" not in out.stdout.splitlines()[-1], out.stdout[-2000:]
