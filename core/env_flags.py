"""Yes/no environment variables (``CISTRACK_BACKGROUND_COMPILE``, ``CISTRACK_FULL_EXIT``), read one way."""
from __future__ import annotations

import os

from cistrack.errors import ConfigError

__all__ = ["env_flag"]

_YES = ("1", "yes", "true", "on")
_NO = ("0", "no", "false", "off")


def env_flag(name: str) -> bool | None:
    """``$name`` as True (1, yes, true, on), False (0, no, false, off) or None (unset, empty or
    ``auto``: the default); any letter case. ConfigError naming the variable for anything else, so
    that a value meant as "no" never does the opposite."""
    text = os.environ.get(name, "").strip().lower()
    if text in ("", "auto"):
        return None
    if text in _YES or text in _NO:
        return text in _YES
    raise ConfigError(f"environment variable {name}={os.environ[name]!r}: give 1, yes, true or on; 0, no, false or "
                      "off; or leave it unset (auto)")
