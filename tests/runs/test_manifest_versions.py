"""The manifest's versions: Python, numpy, cistrack and every distribution that provides a plugin."""
from __future__ import annotations

import platform
from importlib import metadata

import numpy as np

from cistrack.plugin.registry import default_registry
from cistrack.results.store import versions


def test_versions_name_python_numpy_and_cistrack():
    out = versions()
    assert out["python"] == platform.python_version()
    assert out["numpy"] == np.__version__
    assert out["cistrack"] == metadata.version("cistrack")


def test_versions_give_each_plugin_distribution_its_installed_version():
    registry = default_registry()
    dists = {dist for dist, _ep, _mod in registry.plugins}
    out = versions(registry)
    assert "cistrack" in dists
    for dist in dists:
        assert out[dist] == metadata.version(dist)
