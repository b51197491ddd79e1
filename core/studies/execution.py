"""Running a study's runs through an executor, and what each run left on disk afterwards.

A worker's answer is not the truth about a run: a run whose results could not be written (a full
disk) still returns a summary, a killed worker returns nothing, and a run can be left "running".
So after the executor has finished, every run is checked where its results are
(:func:`cistrack.studies.resume.run_state`), and a run that is not done there is reported with the
reason: its manifest's status and failure, or what its worker said when no manifest was written.
"""
from __future__ import annotations

import concurrent.futures as cf
import sys
from pathlib import Path
from typing import Any, Callable, Sequence

from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.run_status import run_status
from cistrack.results.store import read_manifest
from cistrack.studies.resume import run_state

__all__ = ["run_all", "run_problems", "shutdown"]


def run_all(ex: cf.Executor, todo: Sequence[Any], fn: Callable[[Any], Any], bar: Any = None) -> dict[str, str]:
    """Submit ``fn(spec)`` for every spec of ``todo`` and wait for all; returns what each run's
    worker said that was not a normal end (run id -> text), e.g. "status failed: ..." or the
    exception it raised. A run raising an exception never stops the others; its reason goes to
    ``error.txt`` in its directory (when it can be written) and to stderr."""
    said: dict[str, str] = {}
    futures = {ex.submit(fn, s): s for s in todo}
    for fut in cf.as_completed(futures):
        spec = futures[fut]
        try:
            summary = fut.result()
            if summary.status not in ("finished", "filter-failed"):
                said[spec.run_id] = f"{summary.status}" + (f": {summary.failure}" if summary.failure else "")
            if bar is not None:
                bar.set_postfix_str(f"{spec.run_id}: {summary.status}, {summary.verdict.kind}")
        except Exception as exc:  # one failing run must not stop the study
            said[spec.run_id] = f"{type(exc).__name__}: {exc}"
            try:
                Path(spec.out_dir).mkdir(parents=True, exist_ok=True)
                write_text_atomic(Path(spec.out_dir) / "error.txt", f"{type(exc).__name__}: {exc}\n")
            except OSError:  # a full disk: the reason is still printed and reported
                pass
            print(f"run {spec.run_id} failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        if bar is not None:
            bar.update(1)
    return said


def shutdown(ex: cf.Executor, cancel: bool) -> None:
    """Shut ``ex`` down, waiting for its workers; ``cancel``: runs not started yet never start
    (the study was interrupted)."""
    try:
        ex.shutdown(wait=True, cancel_futures=cancel)
    except TypeError:  # an executor whose shutdown takes no cancel_futures (older Dask)
        ex.shutdown(wait=True)


def run_problems(specs: Sequence[Any], said: dict[str, str]) -> list[tuple[str, str]]:
    """(run id, why) for every run of ``specs`` that is not done on disk now, in plan order."""
    out = []
    for s in specs:
        if run_state(s.out_dir, s.fingerprint) == "done":
            continue
        out.append((s.run_id, _why(Path(s.out_dir), s.fingerprint, said.get(s.run_id))))
    return out


def _why(d: Path, fingerprint: str, said: str | None) -> str:
    """Why the run in ``d`` is not done, from its manifest, else from what its worker said."""
    worker = f"; its worker said: {said}" if said else ""
    if not (d / "manifest.json").is_file():
        return f"no manifest.json was written in {d}" + (worker or "; the run never started")
    try:
        status, reason = run_status(d)
        man = read_manifest(d)
    except (OSError, ValueError) as exc:
        return f"its manifest {d / 'manifest.json'} cannot be read ({exc}){worker}"
    if man.get("status") == "running":
        proc = man.get("process") or {}
        gone = ", which is gone" if status == "interrupted" else ""
        return (f"its manifest still says 'running' (process {proc.get('pid', '?')} on {proc.get('host', '?')}"
                f"{gone}): the end of the run was never recorded{worker}")
    if status in ("finished", "filter-failed"):
        if fingerprint and man.get("fingerprint") != fingerprint:
            return f"its results are of another scenario or seed (fingerprint differs){worker}"
        return f"{status}, but {d / 'steps.parquet'} is missing" + (f" ({reason})" if reason else "") + worker
    return status + (f": {reason}" if reason else "") + ("" if reason else worker)
