"""Shared fixtures. Components come from the real registry (entry points of the installed
package); nothing of cistrack's own is mocked."""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def registry():
    from cistrack.plugin.registry import load_registry

    return load_registry()
