"""pyproject.toml lists every package directory, so no module or data file is left out of a wheel."""
from __future__ import annotations

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]


def _package_dirs() -> set[str]:
    names = set()
    for prefix, base in (("cistrack", ROOT / "core"), ("cistrack.plugins", ROOT / "plugins")):
        for d in [base, *[p for p in base.rglob("*") if p.is_dir()]]:
            if "__pycache__" in d.parts or not any(f.is_file() for f in d.iterdir()):
                continue
            rel = d.relative_to(base).parts
            names.add(".".join((prefix, *rel)))
    return names


def test_every_package_directory_is_listed_in_pyproject():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())
    listed = set(conf["tool"]["setuptools"]["packages"])
    assert _package_dirs() - listed == set()


def test_license_is_an_spdx_expression():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert isinstance(conf["project"]["license"], str)
