"""Writing an export (a CCSDS OEM or OPM, or another registered exporter's file) whole or not at all,
and never silently over a different one.

``cistrack export RUN`` without ``--out`` writes ``RUN/estimate.<format>``, a file made from the
run's own results: exporting again with the same options rewrites the same content, which is
fine; but another ``--step`` or a ``--predict`` would replace one orbit message with another,
and :func:`write_export` refuses that unless told to (``--overwrite``), as an existing ``--out``
file is refused. The comparison skips CCSDS's ``CREATION_DATE`` line (the time of writing).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from cistrack.errors import CistrackError, ConfigError
from cistrack.results.atomic_files import atomic_target

__all__ = ["write_export", "same_export"]

_WRITING_TIME = (b"CREATION_DATE",)
"""Line starts that say when a file was written, not what it holds."""


def same_export(a: bytes, b: bytes) -> bool:
    """Whether two exported files hold the same message, apart from when they were written."""
    def content(data: bytes) -> list[bytes]:
        return [line for line in data.splitlines() if not line.lstrip().startswith(_WRITING_TIME)]

    return content(a) == content(b)


def write_export(exporter: Any, out: Path, estimates: Any, meta: dict[str, Any], *, format: str, named: bool,
                 overwrite: bool) -> None:
    """``exporter.write`` to ``out`` through a temporary file and a rename. ``named``: ``out`` was
    given as ``--out`` (refused earlier when it exists without ``overwrite``; errors name it so);
    otherwise ``out`` is the default file in the run's directory, and one there holding a different
    export is refused (:class:`ConfigError`, nothing changed) unless ``overwrite``."""
    try:
        with atomic_target(out) as tmp:  # a full disk leaves no partial file under the final name
            exporter.write(tmp, estimates, meta)
            if not named and not overwrite:
                _check_default_file(out, tmp)
    except OSError as exc:
        raise CistrackError(("--out " if named else "") + f"{out}: cannot write the {format} file "
                            f"({exc.strerror or exc}); nothing was written there") from None


def _check_default_file(out: Path, new: Path) -> None:
    """Refuse replacing the default file ``out`` with ``new`` when they differ."""
    if not out.is_file() or same_export(out.read_bytes(), new.read_bytes()):
        return
    raise ConfigError(f"{out}: already holds a different export (made with other options, e.g. another --step or "
                      "--predict); give --out FILE to write this one beside it, or add --overwrite to replace it")
