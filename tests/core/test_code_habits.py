"""Habits checked on every run of the suite: ruff finds nothing in the tree (pycodestyle, pyflakes
and mccabe complexity, C901), and mypy finds nothing in the public API, the interfaces, the model
types and the plugin machinery (configured in pyproject.toml). Function length and parameter
count: test_function_sizes.py."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TYPED = ["cistrack.api", "cistrack.interfaces", "cistrack.model", "cistrack.plugin", "cistrack._moved"]


def test_ruff_finds_nothing():
    proc = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise",
                           "core", "plugins", "tests", "benchmarks", "examples"],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def _link_tree(dest: Path) -> Path:
    """core/ as ``cistrack/`` and plugins/ as ``cistrack/plugins``, made of links, as installed."""
    pkg = dest / "cistrack"
    for src in (ROOT / "core").rglob("*"):
        if "__pycache__" in src.parts or src.is_dir():
            continue
        target = pkg / src.relative_to(ROOT / "core")
        target.parent.mkdir(parents=True, exist_ok=True)
        os.symlink(src, target)
    os.symlink(ROOT / "plugins", pkg / "plugins")
    return dest


def test_mypy_finds_nothing_in_the_public_api_and_the_interfaces(tmp_path):
    tree = _link_tree(tmp_path / "src")
    args = [sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
            "--cache-dir", str(tmp_path / "cache"), "--python-executable", sys.executable]
    for package in TYPED:
        args += ["-p", package]
    proc = subprocess.run(args, capture_output=True, text=True, cwd=tree, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
