"""One version, written once (pyproject.toml) and read everywhere else from the installed
metadata, and the one the documentation's deprecation promises speak of."""
from __future__ import annotations

import re
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import cistrack
from cistrack._moved import MOVED

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
API_DOC = (ROOT / "docs" / "python-api.md").read_text()


def _release(text: str) -> tuple[int, int]:
    major, minor = text.split(".")[:2]
    return int(major), int(minor)


def test_the_installed_metadata_is_pyprojects_version():
    written = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert metadata.version("cistrack") == written


def test_cistrack_version_prints_the_installed_version():
    out = subprocess.run([sys.executable, "-m", "cistrack.cli", "--version"], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"cistrack {metadata.version('cistrack')}"
    assert cistrack.__version__ == metadata.version("cistrack")


def test_the_api_page_names_the_installed_release():
    named = re.search(r"This page describes cistrack (\d+\.\d+)", API_DOC)
    assert named, "docs/python-api.md should say which release it describes"
    assert _release(named.group(1)) == _release(cistrack.__version__)


def test_the_version_is_one_where_the_documented_moves_have_happened_and_their_aliases_remain():
    moved_in = re.search(r"In (\d+\.\d+) the framework moved", API_DOC).group(1)
    kept_until = re.search(r"Until (\d+\.\d+) the old package path", API_DOC).group(1)
    assert _release(moved_in) <= _release(cistrack.__version__) < _release(kept_until)
    assert "cistrack.belief" in MOVED  # moved in 0.2, its old path still kept
