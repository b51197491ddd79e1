"""Former name of :mod:`.orbit_catalog` (the periodic orbit catalog), kept only as an alias.

Why it exists: an install made before the rename records the entry point
``orbit-catalog = cistrack.plugins.dynamics.catalog`` in its metadata until it is reinstalled
(``pip install -e .`` rewrites it); this alias keeps such installs loading the catalog. New
code imports :mod:`cistrack.plugins.dynamics.orbit_catalog`. Remove at the next release.
"""
from __future__ import annotations

from .orbit_catalog import *  # noqa: F401,F403  (the alias re-exports the catalog unchanged)
from .orbit_catalog import __all__, cistrack_register  # noqa: F401
