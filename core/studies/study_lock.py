"""One ``cistrack study run`` at a time per study directory.

Two study processes writing into one directory would run the same runs at once, each replacing
the other's files (every manifest then reads "failed"). So ``study run`` holds an exclusive
lock on ``<study dir>/.study.lock`` from before it writes ``study.json`` until its last run has
ended: an advisory ``flock`` that the operating system releases when the process ends in any
way, ``kill -9`` included, so a killed study never leaves the directory locked. The lock file
itself stays (it is empty but for the holder's process id, which the refusal names).

The runs themselves hold a shared lock on ``<study dir>/.study-runs.lock`` while they write
(:func:`hold_runs_lock`, taken in the worker process), so that a new study process also waits for
the workers of one that was killed until they have ended (they end with it, see
:mod:`cistrack.studies.workers`), instead of running the same runs beside them.
"""
from __future__ import annotations

import contextlib
import os
import sys
import time
from pathlib import Path
from typing import Iterator

from cistrack.errors import CistrackError
from cistrack.results.dir_lock import holding, lock_holder, open_lock, try_lock
from cistrack.results.output_paths import STUDY_LOCK, STUDY_RUNS_LOCK

__all__ = ["StudyBusy", "study_lock", "hold_runs_lock", "running_study", "RUNS_LOCK"]

RUNS_LOCK = STUDY_RUNS_LOCK
"""Shared-locked by every run while it writes into the study directory."""
WAIT_FOR_RUNS_S = 60.0
"""How long a new study waits for the runs of an ended study process to end (they are told to
stop when that process ends) before it gives up."""


class StudyBusy(CistrackError):
    """Another study process (or its runs) is writing into the study directory."""


_try_lock, _open, _holder = try_lock, open_lock, lock_holder  # the names this module had


@contextlib.contextmanager
def study_lock(directory: str | Path, where: str = "--out") -> Iterator[None]:
    """Hold the study directory's lock for the block; raise :class:`StudyBusy` naming ``where``
    at once if another process holds it, and after :data:`WAIT_FOR_RUNS_S` s if runs of an ended
    study process are still writing there."""
    d = Path(directory)
    with holding(d / STUDY_LOCK, where, lambda holder: StudyBusy(
            f"{where} {d}: another 'cistrack study run'{holder} is running a study in this directory; "
            f"wait for it to end, or give another {where}")):
        _wait_for_runs(d, where)
        yield


def _wait_for_runs(d: Path, where: str) -> None:
    """Wait until no run holds the runs lock (the workers of a killed study process end within
    seconds); raise :class:`StudyBusy` if they have not after :data:`WAIT_FOR_RUNS_S` s."""
    fd = _open(d / RUNS_LOCK, where)
    try:
        deadline = time.monotonic() + WAIT_FOR_RUNS_S
        while not _try_lock(fd):
            if time.monotonic() > deadline:
                raise StudyBusy(f"{where} {d}: runs of an earlier study process are still writing in this "
                                f"directory {WAIT_FOR_RUNS_S:g} s after it ended; wait for them to end, or "
                                f"give another {where}")
            time.sleep(0.2)
    finally:
        os.close(fd)


@contextlib.contextmanager
def hold_runs_lock(study_dir: str | Path) -> Iterator[None]:
    """Hold a shared lock on the study's runs lock while a run writes there (best effort: a
    directory where the lock file cannot be made runs without it)."""
    try:
        fd = os.open(Path(study_dir) / RUNS_LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield
        return
    try:
        if sys.platform != "win32":
            import fcntl
            fcntl.flock(fd, fcntl.LOCK_SH)
        yield
    finally:
        os.close(fd)


def running_study(directory: str | Path) -> str | None:
    """Whether a ``cistrack study run`` holds the lock of the study ``directory`` now: its holder in
    :func:`~cistrack.results.dir_lock.lock_holder`'s words (`` (process PID on HOST)``, or "" when
    unknown), or None when none does. Looks without creating the lock file; a shared lock taken and
    given back at once, so that a study starting at the same instant is not kept out for longer."""
    try:
        fd = os.open(Path(directory) / STUDY_LOCK, os.O_RDONLY)
    except OSError:
        return None
    try:
        return None if _try_lock(fd, shared=True) else _holder(fd)
    finally:
        os.close(fd)
