"""Advisory locks on results directories: one writer at a time.

An exclusive ``flock`` on a lock file in the directory, which the operating system releases when
the process ends in any way (``kill -9`` included), so a killed process never leaves the directory
locked. The lock file itself stays (empty but for the holder's process id and host, which a
refusal names). ``cistrack run`` holds :data:`RUN_LOCK` of its results directory for the whole run
(:func:`run_lock`); a study holds its own lock files (:mod:`cistrack.studies.study_lock`, built on
the functions here).
"""
from __future__ import annotations

import contextlib
import os
import socket
import sys
from pathlib import Path
from typing import Callable, Iterator

from cistrack.errors import CistrackError
from cistrack.results.atomic_files import remove_stale_temporaries
from cistrack.results.output_paths import FIT_LOCK, RUN_LOCK

__all__ = ["RunBusy", "run_lock", "fit_lock", "holding", "try_lock", "open_lock", "lock_holder", "note_holder", "RUN_LOCK",
           "check_no_writer", "results_stamp", "check_unchanged", "check_still_as_read"]


class RunBusy(CistrackError):
    """Another process is writing a run into the results directory."""


def try_lock(fd: int, shared: bool = False) -> bool:
    """Take an advisory lock on ``fd`` without waiting; False if another process holds it."""
    if sys.platform == "win32":  # pragma: no cover (no shared locks there: exclusive on one byte)
        import msvcrt
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
            return True
        except OSError:
            return False
    import fcntl
    try:
        fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False


def open_lock(path: Path, where: str) -> int:
    """Open (create) the lock file ``path``; a :class:`CistrackError` naming ``where`` if it cannot."""
    try:
        return os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise CistrackError(f"{where} {path.parent}: cannot create the lock file {path.name} "
                            f"({exc.strerror or exc})") from None


def lock_holder(fd: int) -> str:
    """`` (process PID on HOST)`` as the holder wrote it into the lock file, or "" if unknown."""
    try:
        text = os.pread(fd, 200, 0).decode("utf-8", "replace").strip()
    except (OSError, AttributeError):
        text = ""
    return f" (process {text})" if text else ""


def note_holder(fd: int) -> None:
    """Write this process's id and host into the locked file (for the refusal of the next one)."""
    with contextlib.suppress(OSError, AttributeError):  # a full disk: no name, the lock still holds
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()} on {socket.gethostname()}\n".encode(), 0)


@contextlib.contextmanager
def holding(path: Path, where: str, refusal: Callable[[str], Exception]) -> Iterator[None]:
    """Hold the exclusive lock of the lock file ``path`` for the block; at once raise
    ``refusal(holder)`` (``holder``: :func:`lock_holder`'s words) if another process holds it."""
    fd = open_lock(path, where)
    try:
        if not try_lock(fd):
            raise refusal(lock_holder(fd))
        note_holder(fd)  # who holds it, for the next refusal
        yield
    finally:
        os.close(fd)  # releases the lock


@contextlib.contextmanager
def run_lock(directory: str | Path, where: str = "--out") -> Iterator[None]:
    """Hold the run lock of the results directory ``directory`` for the block; raise
    :class:`RunBusy` naming ``where``, the directory and the other process at once if another
    process holds it."""
    d = Path(directory)
    with holding(d / RUN_LOCK, where, lambda holder: RunBusy(
            f"{where} {d}: another 'cistrack run'{holder} is writing its results in this directory; "
            "wait for it to end, or give another --out")):
        remove_stale_temporaries(d)  # half-written files of a run killed mid-write; no writer is live now
        yield


@contextlib.contextmanager
def fit_lock(directory: str | Path, where: str = "--out") -> Iterator[None]:
    """Hold the fit lock of the fit directory ``directory`` for the block (a whole fit: its filter
    run takes the run lock inside it); raise :class:`RunBusy` at once if another process holds it."""
    d = Path(directory)
    with holding(d / FIT_LOCK, where, lambda holder: RunBusy(
            f"{where} {d}: another 'cistrack fit'{holder} is writing its results in this directory; "
            "wait for it to end, or give another --out")):
        remove_stale_temporaries(d)
        yield



def check_no_writer(directory: str | Path, doing: str, runs: bool = True) -> None:
    """Refuse (:class:`RunBusy`) to read ``directory``'s results for ``doing`` (e.g. "export") while a
    ``cistrack fit`` or (``runs``) a ``cistrack run`` holds its lock: they are being replaced, and
    what was read would describe the old orbit beside the new results. Takes and releases a shared
    lock; a lock file that cannot be opened is passed over."""
    d = Path(directory)
    for name, who in ((FIT_LOCK, "cistrack fit"), (RUN_LOCK, "cistrack run"))[:2 if runs else 1]:
        try:
            fd = os.open(d / name, os.O_RDONLY)
        except OSError:
            continue
        try:
            free = try_lock(fd, shared=True)
            holder = "" if free else lock_holder(fd)
        finally:
            os.close(fd)
        if not free:
            raise RunBusy(f"{d}: a '{who}'{holder} is writing its results in this directory; no {doing} of it "
                          "until it ends (it would describe the orbit being replaced)")


_RECORDS = ("fit.json", "manifest.json")
"""The records whose change says a results directory was written again (:func:`results_stamp`)."""


def results_stamp(directory: str | Path) -> tuple:
    """What identifies the results of ``directory`` now: (name, inode, size, mtime in ns) of its
    ``fit.json`` and ``manifest.json`` (None for one that is missing)."""
    out = []
    for name in _RECORDS:
        try:
            st = os.stat(Path(directory) / name)
            out.append((name, st.st_ino, st.st_size, st.st_mtime_ns))
        except OSError:
            out.append((name, None))
    return tuple(out)


def check_unchanged(directory: str | Path, stamp: tuple, doing: str) -> None:
    """Refuse (:class:`RunBusy`) to write ``doing``'s file when ``directory``'s results are no longer
    those of ``stamp`` (:func:`results_stamp`, taken when they were read): a fit or run wrote them
    again meanwhile, and the file would describe the orbit it replaced."""
    if results_stamp(directory) != stamp:
        raise RunBusy(f"{directory}: its results were written again while the {doing} was made (a new 'cistrack fit' "
                      f"or 'cistrack run' there); nothing was written: run the {doing} again")


def check_still_as_read(directory: str | Path, stamp: tuple, doing: str) -> None:
    """Before ``doing``'s file is written: no fit or run writes in ``directory`` now
    (:func:`check_no_writer`), and none wrote its results since ``stamp`` was taken (:func:`check_unchanged`)."""
    check_no_writer(directory, doing)
    check_unchanged(directory, stamp, doing)
