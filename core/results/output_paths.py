"""Where results may be written: checked before anything is computed.

A results directory is either new, empty, or an earlier cistrack results directory (it holds a
``manifest.json``); anything else is refused, so that starting a run never deletes or replaces
files that cistrack did not write. The directory is created here, so an unwritable place fails
at once with the reason, not after the run has computed every step.
"""
from __future__ import annotations

from pathlib import Path

from cistrack.errors import ConfigError

__all__ = ["check_output_dir"]


def check_output_dir(directory: str | Path, where: str) -> Path:
    """Create ``directory`` (parents included) or check that it may hold results; return it.

    Raises :class:`ConfigError` naming ``where`` (a flag or key) if it exists and is not a
    directory, is a non-empty directory without a cistrack ``manifest.json``, or cannot be
    created or written."""
    d = Path(directory)
    try:  # a parent that may not be searched (EACCES) answers here, not with a traceback
        if d.exists() and not d.is_dir():
            raise ConfigError(f"{where} {d}: exists and is not a directory; give a new directory or an "
                              "earlier results directory")
        if d.is_dir() and any(d.iterdir()) and not (d / "manifest.json").is_file():
            raise ConfigError(f"{where} {d}: is not empty and holds no cistrack manifest.json; results go "
                              "to a new or empty directory, or replace an earlier run's results directory")
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot look there ({exc.strerror or exc})") from None
    try:
        d.mkdir(parents=True, exist_ok=True)
        probe = d / ".cistrack-write-test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise ConfigError(f"{where} {d}: cannot write there ({exc.strerror or exc})") from None
    return d
