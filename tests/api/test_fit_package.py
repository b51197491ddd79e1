"""``cistrack.fit`` is both the package cistrack.fit and the function cistrack.api.fit: every way of
importing the package's modules works, and calling the package fits."""
from __future__ import annotations

import subprocess
import sys

import pytest

import cistrack as ct
from cistrack.errors import ConfigError


def _run(code: str) -> str:
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def test_a_fit_module_imports_with_a_dotted_name_and_an_alias():
    assert _run("import cistrack.fit.least_squares as m; print(m.__name__)") == "cistrack.fit.least_squares"


def test_the_package_is_reached_as_an_attribute_of_cistrack():
    assert _run("import cistrack; print(cistrack.fit.fit_orbit.__name__)") == "fit_orbit"


def test_calling_the_package_is_the_api_fit():
    with pytest.raises(ConfigError, match="no-such-file.psv"):
        ct.fit("no-such-file.psv")


def test_importing_cistrack_still_does_not_import_the_fit_package():
    assert _run("import sys, cistrack; print('cistrack.fit' in sys.modules)") == "False"
