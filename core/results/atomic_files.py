"""Writing a file so that it is either whole or absent: a temporary file in the same folder, then
a rename over the target.

A write that fails half-way (a full disk, a quota, a killed process) would otherwise leave a
truncated or 0-byte file under the final name, which later commands read as a result, or which
blocks the next attempt (an existing ``--out`` file is refused). Here the data first goes to a
hidden temporary file beside the target (``.NAME.XXXX.tmp``, NAME shortened to keep it within the
file system's limit on a name; same file system, so the rename
cannot fail half-way), which is removed again when writing fails, and only a complete file is
renamed (:func:`os.replace`) onto the target.
"""
from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
from pathlib import Path
from typing import Iterator

__all__ = ["atomic_target", "write_text_atomic", "write_bytes_atomic", "write_text_new", "remove_stale_temporaries"]


@contextlib.contextmanager
def atomic_target(path: str | Path, tmp_name: str | None = None) -> Iterator[Path]:
    """Yield a fresh temporary path beside ``path`` to write to; on leaving the block without an
    exception it replaces ``path``, on an exception (of any kind) it is deleted and ``path`` is
    left as it was (an OSError that names no file is raised again naming ``path``). The temporary file exists (empty) when the block starts, unless ``tmp_name``
    names it: a fixed name beside ``path``, for a file only one process ever writes (a run's own
    tables), which a failed earlier attempt's leftover can never block."""
    target = Path(path)
    _refuse_special(target)
    tmp = target.parent / tmp_name if tmp_name else _new_file(target)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError) and exc.errno is not None and not exc.filename:
            # a failed write names no file ("No space left on device"): name the one being written
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise


def _refuse_special(target: Path) -> None:
    """OSError when ``target`` (or what its symbolic link points to) is a device, pipe or socket:
    a rename would replace that node (e.g. /dev/full) with a regular file."""
    import stat

    try:
        mode = os.stat(target).st_mode
    except OSError:
        return
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise OSError(errno.EINVAL, "not a regular file (a device, pipe or socket), which is never replaced; "
                                    "give the path of a regular file", str(target))


def _new_file(target: Path) -> Path:
    """Create an empty, new file beside ``target`` with the permissions an ordinary ``open`` would
    give it (0o666 less the umask; ``tempfile.mkstemp`` would make it private)."""
    for _ in range(100):
        tmp = target.parent / f".{_name_part(target)}.{secrets.token_hex(4)}.tmp"
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"{target.parent}: no free temporary name for {target.name}")


_TEMPORARY_EXTRA = len("..12345678.tmp")
"""How much longer a temporary file's name is than the part of the target's name it keeps."""


def _name_part(target: Path) -> str:
    """As much of ``target``'s name as a temporary name beside it can keep within the folder's
    limit on a name's length (255 bytes where it cannot be asked): a target's name of 242 to 255
    bytes, which the file system takes, had made a temporary name too long, and the write was refused
    with "File name too long" (probe J8)."""
    try:
        limit = os.pathconf(target.parent if str(target.parent) else ".", "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    room = max(1, (limit if limit and limit > 0 else 255) - _TEMPORARY_EXTRA)
    encoded = os.fsencode(target.name)
    if len(encoded) <= room:
        return target.name
    return encoded[:room].decode("utf-8", "ignore") or "x"


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename (never a partial file)."""
    with atomic_target(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)


def write_text_atomic(path: str | Path, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename (never a partial file)."""
    write_bytes_atomic(path, text.encode(encoding))


def write_text_new(path: str | Path, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path``, which must not exist, through a temporary file: the complete
    file appears under ``path`` at once (a hard link, which never replaces a file), or nothing
    does. Raises FileExistsError when ``path`` exists (also when it appeared meanwhile) and
    OSError when writing fails (the temporary file is removed then)."""
    target = Path(path)
    if os.path.lexists(target):
        raise FileExistsError(errno.EEXIST, "File exists", str(target))
    tmp = _new_file(target)
    try:
        with open(tmp, "wb") as fh:
            fh.write(text.encode(encoding))
        try:
            os.link(tmp, target)
        except FileExistsError:
            raise
        except OSError:  # a file system without hard links: a rename, unless the name appeared meanwhile
            if os.path.lexists(target):
                raise FileExistsError(errno.EEXIST, "File exists", str(target)) from None
            os.rename(tmp, target)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


_TEMPORARY = re.compile(r"^\..+\.[0-9a-f]{8}\.tmp$")
"""The names :func:`_new_file` gives its temporary files."""


def remove_stale_temporaries(directory: str | Path) -> int:
    """Delete the temporary files of writes into ``directory`` that a killed process (``kill -9``)
    left half-written; call it only while holding the directory's lock (no other writer then).
    Returns how many were removed."""
    removed = 0
    with contextlib.suppress(OSError):
        for entry in os.scandir(directory):
            if _TEMPORARY.match(entry.name) and entry.is_file(follow_symlinks=False):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)
                    removed += 1
    return removed
