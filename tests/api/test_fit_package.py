"""``cistrack.fit`` is the function cistrack.api.fit; the package that had its name was split into
cistrack.least_squares (the mathematics) and cistrack.fitting (the ``cistrack fit`` workflow), and
every old import path of it still works, with a DeprecationWarning naming the new one."""
from __future__ import annotations

import inspect
import subprocess
import sys
import typing

import pytest

import cistrack as ct
import cistrack.api
from cistrack.errors import ConfigError
from cistrack.fitting.from_observations import ObjectFit


def _run(code: str) -> tuple[str, str]:
    """stdout and stderr of ``code`` in a fresh interpreter that shows every warning."""
    code = "import warnings\nwarnings.simplefilter('always')\n" + code
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip(), proc.stderr


def test_cistrack_fit_is_the_api_function():
    assert inspect.isfunction(ct.fit) and ct.fit is cistrack.api.fit


def test_calling_it_fits_the_files_and_refuses_a_missing_one_by_name():
    with pytest.raises(ConfigError, match="no-such-file.psv"):
        ct.fit("no-such-file.psv")


def test_it_is_annotated_to_return_a_list_of_the_exported_object_fit():
    public = {n: getattr(cistrack.api, n) for n in cistrack.api.__all__}
    assert typing.get_type_hints(ct.fit, localns=public)["return"] == list[ObjectFit]


def test_object_fit_is_exported_from_the_api_and_the_package():
    assert cistrack.api.ObjectFit is ObjectFit and ct.ObjectFit is ObjectFit
    assert "ObjectFit" in cistrack.api.__all__ and "ObjectFit" in ct.__all__


def test_importing_cistrack_imports_neither_fit_package():
    out, _ = _run("import sys, cistrack\n"
                  "print([m for m in ('cistrack.least_squares', 'cistrack.fitting') if m in sys.modules])")
    assert out == "[]"


def test_the_old_package_path_imports_its_names_with_a_warning_naming_the_new_package():
    out, err = _run("from cistrack.fit import fit_orbit, FitOptions\nprint(fit_orbit.__module__)")
    assert out == "cistrack.least_squares.differential_correction"
    assert "<string>:3: DeprecationWarning: cistrack.fit moved to cistrack.least_squares" in err


def test_an_old_module_path_imports_its_names_from_the_moved_module():
    out, err = _run("from cistrack.fit.least_squares import fit_orbit\nprint(fit_orbit.__module__)")
    assert out == "cistrack.least_squares.differential_correction"
    assert "cistrack.fit.least_squares moved to cistrack.least_squares.differential_correction" in err


def test_an_old_module_path_imports_with_a_dotted_name_and_an_alias():
    out, _ = _run("import cistrack.fit.least_squares as m\nimport cistrack.fit.from_observations as w\n"
                  "print(m.__name__, w.__name__)")
    assert out.split() == ["cistrack.least_squares.differential_correction", "cistrack.fitting.from_observations"]


def test_importing_an_old_path_leaves_cistrack_fit_the_function():
    out, _ = _run("import cistrack.fit.least_squares\nimport cistrack.fit\nimport cistrack as ct\n"
                  "print(ct.fit.__module__, ct.fit.__name__)")
    assert out.split() == ["cistrack.api", "fit"]
