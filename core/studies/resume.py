"""Which runs of a study are done, stale or still to do (a study resumes from this).

A run is done when its manifest says "finished" or "filter-failed", its table is merged (and its
Parquet footer readable: a truncated or overwritten table is run again), its summary reads back
(a manifest cut short, or damaged: not a JSON object, a summary that is not one, is run again), and its
fingerprint (:mod:`cistrack.results.fingerprint`) matches the run the study would make now. A run left
"running" (killed), "interrupted" or "failed" is run again, as is a finished run whose scenario,
seed or measurement file changed ("stale").
"""
from __future__ import annotations

from pathlib import Path

from cistrack.evaluation.run_summary import RunSummary
from cistrack.results.store import read_manifest, steps_readable
from cistrack.results.run_status import process_gone

__all__ = ["DONE", "run_state", "is_done"]

DONE = ("finished", "filter-failed")
"""Manifest statuses of runs that ended on their own."""


def _manifest(out_dir: str) -> dict | None:
    """The run's manifest; None when there is none or it cannot be read (truncated, or not a JSON
    object)."""
    try:
        return read_manifest(out_dir)
    except (OSError, ValueError):  # ValueError: not JSON (cut short), or JSON but not an object
        return None


def _summary_reads_back(man: dict) -> bool:
    try:
        RunSummary.from_dict(man.get("summary"))
    except ValueError:
        return False
    return True


def _ended(man: dict, out_dir: str) -> bool:
    """Whether the manifest ``man`` says the run ended on its own, with a run summary that reads
    back, and its table is readable."""
    return man.get("status") in DONE and _summary_reads_back(man) and steps_readable(out_dir)


def run_state(out_dir: str, fingerprint: str = "") -> str:
    """"done" (finished with this fingerprint), "stale" (finished, but its scenario, seed or input
    file changed since: it is rerun), "gone" (left "running" by a process that no longer exists:
    interrupted, see :mod:`cistrack.results.run_status`; it is rerun), "damaged" (its manifest is
    cut short, not a JSON object, or says the run ended with a summary that does not read back: it
    is rerun) or "todo" (missing, interrupted, failed, or running elsewhere)."""
    if not (Path(out_dir) / "manifest.json").exists():
        return "todo"
    man = _manifest(out_dir)
    if man is None or (man.get("status") in DONE and not _summary_reads_back(man)):
        return "damaged"
    if man.get("status") == "running" and process_gone(man.get("process")):
        return "gone"
    if not _ended(man, out_dir):
        return "todo"
    if fingerprint and man.get("fingerprint") != fingerprint:
        return "stale"
    return "done"


def is_done(out_dir: str) -> bool:
    """Whether the run in ``out_dir`` ended (finished or filter-failed) with its summary and table
    readable."""
    man = _manifest(out_dir)
    return man is not None and _ended(man, out_dir)
