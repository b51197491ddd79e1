"""Every module that moved keeps its old import path for a release: the same module object,
with a DeprecationWarning that names the new path and points at the importing line."""
from __future__ import annotations

import importlib
import subprocess
import sys
import warnings

import pytest

from cistrack._moved import MOVED


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_path_gives_the_moved_module_with_a_warning_naming_the_new_path(old):
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=MOVED[old].replace(".", r"\.")):
        module = importlib.import_module(old)
    assert module is importlib.import_module(MOVED[old])


@pytest.mark.parametrize("old", sorted(MOVED))
def test_every_alias_points_at_a_module_that_exists(old):
    assert importlib.util.find_spec(MOVED[old]) is not None


@pytest.mark.parametrize("statement,name", [
    ("from cistrack.plugins.dynamics.compiled import CompiledDynamics", "CompiledDynamics"),
    ("from cistrack.component import check_int", "check_int"),
    ("from cistrack.belief import ParticleCloud", "ParticleCloud"),
    ("from cistrack.run import run_scenario", "run_scenario"),
    ("from cistrack.scenario import load_scenario", "load_scenario"),
    ("from cistrack.results import read_steps", "read_steps"),
    ("from cistrack.frames.earth_moon import EarthMoonFrame", "EarthMoonFrame"),
    ("from cistrack.fit import FitOptions", "FitOptions"),
    ("from cistrack.fit.least_squares import fit_orbit", "fit_orbit"),
    ("from cistrack.fit.from_observations import ObjectFit", "ObjectFit"),
])
def test_old_from_import_in_a_fresh_process_warns_at_the_importing_line(statement, name):
    code = f"import warnings\nwarnings.simplefilter('always')\n{statement}\nprint({name}.__module__)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "<string>:3: DeprecationWarning" in proc.stderr
    assert "cistrack._moved" not in proc.stdout


def test_interfaces_names_are_unchanged_and_import_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from cistrack.interfaces import Clusterer, Dynamics, Filter  # noqa: F401


def test_importing_the_old_run_module_leaves_cistrack_run_the_function():
    import cistrack

    sys.modules.pop("cistrack.run", None)
    with pytest.warns(DeprecationWarning):
        from cistrack.run import run_scenario  # noqa: F401
    assert callable(cistrack.run) and cistrack.run.__module__ == "cistrack.api"


def test_importing_the_old_study_module_leaves_cistrack_study_the_function():
    import cistrack

    sys.modules.pop("cistrack.study", None)
    with pytest.warns(DeprecationWarning):
        from cistrack.study import plan_runs  # noqa: F401
    assert callable(cistrack.study) and cistrack.study.__module__ == "cistrack.api"


def test_old_study_module_imported_first_in_a_fresh_process_leaves_cistrack_study_the_function():
    code = ("import warnings\nwarnings.simplefilter('ignore')\nimport cistrack as ct\n"
            "from cistrack.study import plan_runs\nimport cistrack.study\nprint(ct.study.__module__, plan_runs.__name__)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["cistrack.api", "plan_runs"]


def test_a_name_the_replaced_module_never_had_is_an_attribute_error():
    import cistrack.results

    with pytest.raises(AttributeError, match="no_such_name"):
        cistrack.results.no_such_name  # noqa: B018


@pytest.mark.parametrize("statement", ["from cistrack.scenario import toml_input",
                                       "from cistrack.scenario import limits",
                                       "from cistrack.results import store"])
def test_a_submodule_of_a_package_that_replaced_a_module_imports_without_warning(statement):
    """In a fresh process, where the submodule is not yet imported: it is the package's own
    module, not a name that moved, whatever else the replaced module re-exports."""
    out = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c", statement],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-600:]


@pytest.mark.parametrize("old,name", [("cistrack.run", "run_scenario"), ("cistrack.study", "plan_runs"),
                                      ("cistrack.fit", "fit_orbit")])
def test_old_module_imported_as_a_name_in_a_fresh_process_reaches_the_moved_names_with_a_warning(old, name):
    """``import cistrack.run as pipeline`` binds the function ``cistrack.run``: the moved module's
    public names are on it, so 0.1 code runs unchanged, and the import warns with the new path."""
    code = (f"import warnings\nwarnings.simplefilter('always')\nimport {old} as m\nimport {MOVED[old]} as new\n"
            f"print(m.{name} is new.{name}, callable(m))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["True", "True"]
    assert f"<string>:3: DeprecationWarning: {old} moved to {MOVED[old]}" in proc.stderr


def test_the_api_module_is_an_attribute_of_the_package_without_importing_it_first():
    code = "import cistrack as ct\nprint(ct.api.default_registry is ct.api.__dict__['default_registry'])"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["True"]
