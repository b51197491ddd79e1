"""Limits the framework sets that components must respect too, each checked where the value is
given (a scenario key, a component parameter, a flag):

- :data:`MAX_STEPS`: the most filter steps one run may take; a schedule refuses to plan more
  measurement times than this before it builds them.
- :func:`check_port`: a TCP port a server (the web viewer, a recording server) may listen on.
"""
from __future__ import annotations

import numbers
from typing import Any

from cistrack.errors import ConfigError

__all__ = ["MAX_STEPS", "PORT_MIN", "PORT_MAX", "check_port"]

MAX_STEPS = 1_000_000
"""Most filter steps one run may take. A step costs about 1-25 ms (UKF to a 2,000-particle PGM)
and keeps a results row in memory until the run ends, so a million steps is already hours of
work; the long observation files runs are meant for (400,000 rows) fit well within it."""

PORT_MIN, PORT_MAX = 1, 65535
"""TCP port numbers a server may be asked to listen on (0 means "any free port" to the operating
system, so it is never a port the user can be sent to)."""


def check_port(value: Any, where: str) -> int:
    """``value`` as a TCP port to listen on: an integer in [1, 65535]; a
    :class:`~cistrack.errors.ConfigError` naming ``where`` (a file and key, or a flag) otherwise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{where}: port {value!r} must be an integer from {PORT_MIN} to {PORT_MAX}")
    port = int(value)
    if not PORT_MIN <= port <= PORT_MAX:
        raise ConfigError(f"{where}: port {value} is out of range: allowed {PORT_MIN} to {PORT_MAX}")
    return port
