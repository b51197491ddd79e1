"""Writing an export (a CCSDS OEM or OPM, or another registered exporter's file) whole or not at all,
and never silently over a different one.

``cistrack export RUN`` without ``--out`` writes ``RUN/estimate.<format>``, a file made from the
run's own results: exporting again with the same options rewrites the same content, which is
fine; but another ``--step`` or a ``--predict`` would replace one orbit message with another,
and :func:`write_export` refuses that unless told to (``--overwrite``), as an existing ``--out``
file is refused. The comparison skips CCSDS's ``CREATION_DATE`` line (the time of writing).
"""
from __future__ import annotations

import errno
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cistrack.errors import CistrackError, ConfigError
from cistrack.interrupts import plugin_fault, raise_pending
from cistrack.results.atomic_files import atomic_target

__all__ = ["write_export", "same_export", "ExportWords", "CLI_EXPORT_WORDS", "PYTHON_EXPORT_WORDS"]


@dataclass(frozen=True)
class ExportWords:
    """How an export's refusals name its caller's options: ``cistrack export RUN --out FILE
    --overwrite`` on the command line, ``export_run(RUN, path=FILE, overwrite=True)`` from Python."""

    path: str = "--out"
    """The output file option (``--out FILE: already exists``)."""
    give_path: str = "give --out FILE"
    """What to do to write elsewhere."""
    overwrite: str = "add --overwrite"
    """What to do to allow a replacement."""
    force: str = "add --force"
    """What to do to export a run or fit that did not end well."""
    predict: str = "--predict"
    """The prediction span option (days)."""
    covariance: str = "--covariance"
    """The covariance method option."""
    format: str = "--format"
    """The exporter option."""
    step: str = "--step"
    """The option of an exporter of one step."""

    def option(self, name: str, value: Any) -> str:
        """``--out x.oem`` or ``path='x.oem'``: option ``name`` (a field) with its value."""
        word = getattr(self, name)
        return f"{word}{value!r}" if word.endswith("=") else f"{word} {value}"


CLI_EXPORT_WORDS = ExportWords()
"""The command line's words."""
PYTHON_EXPORT_WORDS = ExportWords(path="path=", give_path="give path=FILE", overwrite="pass overwrite=True",
                                  force="pass force=True", predict="predict_days=", covariance="covariance=",
                                  format="format=", step="step=")
"""The Python functions' words (:func:`cistrack.runs.export.export_run`,
:func:`cistrack.fitting.fit_export.export_fit`)."""

_WRITING_TIME = (b"CREATION_DATE",)
"""Line starts that say when a file was written, not what it holds."""


def same_export(a: bytes, b: bytes) -> bool:
    """Whether two exported files hold the same message, apart from when they were written."""
    def content(data: bytes) -> list[bytes]:
        return [line for line in data.splitlines() if not line.lstrip().startswith(_WRITING_TIME)]

    return content(a) == content(b)


def write_export(exporter: Any, out: Path, estimates: Any, meta: dict[str, Any], *, format: str, named: bool,
                 overwrite: bool, words: ExportWords = CLI_EXPORT_WORDS) -> None:
    """``exporter.write`` to ``out`` through a temporary file and a rename. ``named``: ``out`` was
    given as ``--out`` (``words.path``; refused earlier when it exists without ``overwrite``; errors name it so);
    otherwise ``out`` is the default file in the run's directory, and one there holding a different
    export is refused (:class:`ConfigError`, nothing changed) unless ``overwrite``."""
    try:
        with atomic_target(out) as tmp:  # a full disk leaves no partial file under the final name
            _write_checked(exporter, tmp, estimates, meta, format)
            if not named and not overwrite:
                _check_default_file(out, tmp, words)
            raise_pending()  # a Ctrl-C lost while the export was computed: nothing written (probe J1)
    except OSError as exc:
        raise CistrackError((words.option("path", str(out)) if named else str(out)) + f": cannot write the {format} file "
                            f"({exc.strerror or exc}); nothing was written there") from None


_NOT_A_FILE = (errno.EEXIST, errno.EISDIR, errno.ENOTDIR)
"""What an exporter meets making a directory or a link at the temporary file it is given."""


def _write_checked(exporter: Any, tmp: Path, estimates: Any, meta: dict[str, Any], format: str) -> None:
    """``exporter.write``, an exporter that breaks its contract named (:class:`PluginError`): one
    that raises what is neither cistrack's error nor the system's, calls ``sys.exit``, writes
    nothing, or makes something else than a file at ``tmp`` (which exists, empty: a directory or a
    link made there fails "File exists", which had been said of ``--out``: probe I8)."""
    from cistrack.errors import PluginError, exception_text

    who = f"exporter {format!r} ({type(exporter).__module__})"
    try:
        exporter.write(tmp, estimates, meta)
    except OSError as exc:
        if exc.errno in _NOT_A_FILE and tmp in [Path(f) for f in (exc.filename, exc.filename2) if f]:
            raise PluginError(f"{who} failed: {exception_text(exc)}: it must write a regular file at the path it is "
                              "given (a temporary file beside the export, which exists empty); nothing was "
                              "written") from exc
        raise
    except CistrackError:
        raise
    except BaseException as exc:  # a plugin's fault, named (a KeyboardInterrupt only from a signal)
        if not plugin_fault(exc):
            raise
        raise PluginError(f"{who} failed: {exception_text(exc)}; nothing was written") from exc
    if not tmp.is_file() or tmp.stat().st_size == 0:
        raise PluginError(f"{who} wrote nothing; nothing was written")


def _object_ids(data: bytes) -> list[str]:
    """The values of a CCSDS KVN file's ``OBJECT_ID`` lines (none for another kind of file)."""
    return [line.partition(b"=")[2].strip().decode("utf-8", "replace") for line in data.splitlines()
            if line.lstrip().startswith(b"OBJECT_ID") and b"=" in line]


def _check_default_file(out: Path, new: Path, words: ExportWords) -> None:
    """Refuse replacing the default file ``out`` with ``new`` when they differ, saying whether the
    file there is of another object (another orbit's export written there by name) or of this one."""
    if not out.is_file():
        return
    old_bytes, new_bytes = out.read_bytes(), new.read_bytes()
    if same_export(old_bytes, new_bytes):
        return
    there, here = _object_ids(old_bytes), _object_ids(new_bytes)
    what = (f"an export of another object (OBJECT_ID = {there[0]} there, {here[0]} here), written there by name, "
            f"not the export of {out.parent}" if there and here and there != here else
            f"a different export (made with other options, e.g. another {words.step} or {words.predict})")
    raise ConfigError(f"{out}: already holds {what}; {words.give_path} to write this one beside it, or "
                      f"{words.overwrite} to replace it")
