"""Work in progress."""
from __future__ import annotations

from cistrack.api import hookimpl


@hookimpl
def cistrack_register(registry):
    """Nothing registered yet."""
