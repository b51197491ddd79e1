"""Built-in plugins import cistrack exactly as a third party would (issue 48).

Every module under plugins/ and the plugin template imports only what
:mod:`cistrack.plugin.import_rule` allows: ``cistrack``, :mod:`cistrack.api`, the lower packages
it names and its own plugin family (the template's tests also :mod:`cistrack.testing`).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from cistrack.plugin.import_rule import forbidden_imports, imports_in_source, plugin_family

from source_imports import PLUGINS, ROOT, module_name, sources

TEMPLATE = ROOT / "examples" / "plugin-template"


def _plugin_sources():
    for p in sources(PLUGINS):
        yield pytest.param(p, id=str(p.relative_to(PLUGINS)))


def _template_module(path: Path) -> str:
    """``examples/plugin-template/cistrack_template/srp.py`` -> ``cistrack_template.srp``."""
    parts = path.relative_to(TEMPLATE).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _forbidden(path: Path, module: str, tests: bool = False) -> list[str]:
    imports = imports_in_source(path.read_text(), module, is_package=path.name == "__init__.py")
    return forbidden_imports(module, imports, tests=tests)


@pytest.mark.parametrize("path", list(_plugin_sources()))
def test_built_in_plugin_imports_only_what_a_third_party_may(path):
    assert _forbidden(path, module_name(path)) == [], (
        "import it from cistrack.api or a package cistrack.plugin.import_rule.ALLOWED names, or move it down")


@pytest.mark.parametrize("path", sources(TEMPLATE), ids=lambda p: str(p.relative_to(TEMPLATE)))
def test_plugin_template_imports_only_what_a_third_party_may(path):
    tests = "tests" in path.relative_to(TEMPLATE).parts
    assert _forbidden(path, _template_module(path), tests=tests) == []


def _check(source: str, module: str = "cistrack.plugins.sensors.probe", tests: bool = False) -> list[str]:
    return forbidden_imports(module, imports_in_source(source, module), tests=tests)


def test_a_plugin_may_import_the_public_api_and_top_level_names():
    assert _check("from cistrack.api import hookimpl, default_registry\nfrom cistrack import hookimpl") == []


def test_a_plugin_may_import_the_lower_packages():
    assert _check("import cistrack.units\nfrom cistrack.astro.sky import x\nfrom cistrack.interfaces import Sensor\n"
                  "from cistrack.model.belief import ParticleCloud\nfrom cistrack.least_squares import y") == []


def test_the_pipeline_floors_are_forbidden():
    source = "\n".join(f"import cistrack.{p}.m" for p in ("runs", "fit", "scenario", "results", "evaluation",
                                                          "studies", "cli"))
    assert len(_check(source)) == 7


def test_the_plugin_machinery_is_forbidden():
    assert _check("from cistrack.plugin.hookspecs import hookimpl") == ["cistrack.plugin.hookspecs"]


def test_a_floor_named_from_the_top_level_package_is_forbidden():
    assert _check("from cistrack import runs") == ["cistrack.runs"]


def test_the_own_family_is_allowed_absolute_or_relative():
    assert _check("from cistrack.plugins.sensors.frames import F\nfrom .space_frames import G") == []


def test_another_family_is_forbidden():
    assert _check("from cistrack.plugins.dynamics.cr3bp import CR3BP") == ["cistrack.plugins.dynamics.cr3bp"]


def test_a_relative_import_reaching_another_family_is_forbidden():
    assert _check("from ..dynamics import cr3bp") == ["cistrack.plugins.dynamics"]


def test_a_third_party_may_import_no_built_in_plugin():
    assert _check("from cistrack.plugins.sensors import frames", module="my_package.sensor") == [
        "cistrack.plugins.sensors"]


def test_the_testing_package_is_for_tests_only():
    source = "from cistrack.testing import check_plugin"
    assert _check(source) == ["cistrack.testing"]
    assert _check(source, tests=True) == []


def test_the_family_of_a_built_in_module_is_its_plugin_package():
    assert plugin_family("cistrack.plugins.sensors.frames") == "cistrack.plugins.sensors"
    assert plugin_family("my_package.sensor") is None
