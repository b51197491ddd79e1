"""Study worker processes that never outlive the study process that started them.

``study run`` runs its runs in a :class:`concurrent.futures.ProcessPoolExecutor` (spawned
processes). If the study process is killed (``kill -9``, the machine's OOM killer), nothing
would tell its workers: they were re-parented to init, went on with the runs they held and then
waited forever for more. So each worker, in :func:`init_worker`:

* asks the Linux kernel to send it SIGTERM when its parent ends (``prctl(PR_SET_PDEATHSIG)``
  through ctypes), and checks right after whether the parent already ended;
* starts a watchdog thread that notices the same on any POSIX system (its parent process id
  changes when it is re-parented), sends itself SIGTERM, and ends the process outright if that
  has not ended it within :data:`GRACE_S` s;
* handles SIGTERM by ending the run in progress like Ctrl-C (:class:`~cistrack.errors.RunInterrupted`:
  its completed steps merged and its manifest "interrupted", so a later ``study run`` runs it
  again) and then ending the process; an idle worker ends at once;
* ignores SIGINT: a terminal's Ctrl-C reaches every process of the group, and a worker that
  stopped its run on it was then stopped again by the study's SIGTERM while it wrote its
  manifest, leaving it "running"; the study process alone takes the Ctrl-C and stops its workers.

:func:`run_spec` is what the study submits: one run (:func:`execute_run`) under the study's runs
lock (:func:`cistrack.studies.study_lock.hold_runs_lock`).
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

from cistrack.errors import RunInterrupted

__all__ = ["execute_run", "init_worker", "run_spec", "GRACE_S"]

GRACE_S = 30.0
"""Seconds an orphaned worker is given to end its run (merge its steps, write its manifest)."""
POLL_S = 0.5
"""How often the watchdog looks at the parent process id."""
_PR_SET_PDEATHSIG = 1

_parent: int | None = None
_in_run = False
_stopping: str | None = None


def init_worker(threads: int, parent_pid: int) -> None:
    """Initializer of a study's worker process: ``threads`` numba threads, and the process ends
    when ``parent_pid`` (the study process) does."""
    try:
        import numba
        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    except Exception:
        pass
    global _parent
    _parent = int(parent_pid)
    if os.name != "posix":  # pragma: no cover (Windows ends a pool's workers through their pipes)
        return
    signal.signal(signal.SIGTERM, _on_sigterm)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the study process stops us
    _parent_death_signal(signal.SIGTERM)
    threading.Thread(target=_watch, args=(_parent,), name="cistrack-parent-watch", daemon=True).start()
    if os.getppid() != _parent:  # the parent ended before the kernel was asked to tell us
        os.kill(os.getpid(), signal.SIGTERM)


def _parent_death_signal(sig: int) -> bool:
    """Ask the Linux kernel to send ``sig`` to this process when its parent ends (False where
    that is not available)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent: int) -> None:
    """Watchdog thread: once the parent is gone, SIGTERM to this process, then the end of it
    after :data:`GRACE_S` s whatever it is doing."""
    while os.getppid() == parent:
        time.sleep(POLL_S)
    with contextlib.suppress(OSError):
        os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(GRACE_S)
    os._exit(128 + signal.SIGKILL)


def _parent_gone() -> bool:
    return _parent is not None and os.getppid() != _parent


def _on_sigterm(signum: int, frame: Any) -> None:
    """SIGTERM in a worker: end the run in progress as interrupted (once), or the idle process."""
    global _stopping
    if _stopping is not None:
        return
    _stopping = ("the study process ended" if _parent_gone() else
                 "SIGTERM to a study worker: the study process ended or stopped its workers")
    if _in_run:
        raise RunInterrupted(_stopping if _stopping.startswith("SIGTERM") else f"SIGTERM: {_stopping}")
    os._exit(128 + signal.SIGTERM)


def execute_run(spec: Any) -> Any:
    """Run one study run (a :class:`cistrack.studies.study.RunSpec`) in this process and write it
    to ``spec.out_dir``. Returns its :class:`~cistrack.evaluation.run_summary.RunSummary`."""
    from threadpoolctl import threadpool_limits

    from cistrack.plugin.registry import default_registry
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    reg = default_registry()
    scen = load_scenario(spec.scenario, reg, overrides=spec.overrides)  # validated (and built) once
    observers = []
    if spec.rerun_path:
        observers.append(reg.create("recorder", "rerun", path=spec.rerun_path, frame=scen.recording_frame,
                                    overwrite=True))  # the study's own recording of a run it reruns
    with threadpool_limits(1):  # one BLAS/OpenMP thread: identical numbers whichever worker runs it
        res = run_scenario(scen, seed=spec.seed, registry=reg, output_dir=spec.out_dir, run_id=spec.run_id,
                           observers=observers)
    return res.summary


def run_spec(spec: Any) -> Any:
    """Run one study run (a :class:`cistrack.studies.study.RunSpec`) in this worker; returns its
    summary. A worker told to stop ends its process once the run has ended."""
    from cistrack.studies.study_lock import hold_runs_lock

    global _in_run
    try:
        with hold_runs_lock(Path(spec.out_dir).parent.parent):
            _in_run = True
            try:
                return execute_run(spec)
            finally:
                _in_run = False
    finally:
        if _stopping is not None and _parent is not None:
            os._exit(128 + signal.SIGTERM)
