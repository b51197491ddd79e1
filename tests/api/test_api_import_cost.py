"""``cistrack.api`` is cheap enough for a plugin module to import: the names only running needs load
on first access (PEP 562), the plugin-author names at once."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

import cistrack.api

PIPELINE = ("cistrack.astro", "cistrack.least_squares", "cistrack.results", "cistrack.evaluation",
            "cistrack.scenario", "cistrack.runs", "cistrack.fitting", "cistrack.studies", "cistrack.cli")


def _loaded_after(code: str) -> list[str]:
    probe = f"import sys, json\n{code}\nprint(json.dumps([p for p in {PIPELINE!r} if p in sys.modules]))"
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_importing_the_api_loads_none_of_the_pipeline_packages():
    assert _loaded_after("import cistrack.api") == []


def test_the_plugin_author_names_load_none_of_them_either():
    assert _loaded_after("from cistrack.api import Component, Filter, hookimpl, ParticleCloud, CompiledDynamics, "
                         "MeasurementSet, default_registry, check_int, ConfigError") == []


@pytest.mark.parametrize("name,module", [
    ("Scenario", "cistrack.scenario.loading"), ("RunSummary", "cistrack.evaluation.run_summary"),
    ("Verdict", "cistrack.evaluation.custody"), ("ObjectFit", "cistrack.fitting.from_observations")])
def test_a_run_only_name_is_the_defining_modules_object_on_first_access(name, module):
    import importlib

    assert getattr(cistrack.api, name) is getattr(importlib.import_module(module), name)


def test_every_public_name_is_listed_and_reachable():
    assert all(getattr(cistrack.api, n) is not None for n in cistrack.api.__all__)
    assert set(cistrack.api.__all__) <= set(dir(cistrack.api))


def test_a_name_the_api_does_not_have_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_name"):
        cistrack.api.no_such_name  # noqa: B018
