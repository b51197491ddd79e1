"""Which runs of a study are done, stale or still to do (a study resumes from this).

A run is done when its manifest says "finished" or "filter-failed", its table is merged (and its
Parquet footer readable: a truncated or overwritten table is run again), and its
fingerprint (:mod:`cistrack.results.fingerprint`) matches the run the study would make now. A run left
"running" (killed), "interrupted" or "failed" is run again, as is a finished run whose scenario,
seed or measurement file changed ("stale").
"""
from __future__ import annotations

import json
from pathlib import Path

from cistrack.results.store import read_manifest, steps_readable
from cistrack.results.run_status import process_gone

__all__ = ["DONE", "run_state", "is_done"]

DONE = ("finished", "filter-failed")
"""Manifest statuses of runs that ended on their own."""


def run_state(out_dir: str, fingerprint: str = "") -> str:
    """"done" (finished with this fingerprint), "stale" (finished, but its scenario, seed or input
    file changed since: it is rerun), "gone" (left "running" by a process that no longer exists:
    interrupted, see :mod:`cistrack.results.run_status`; it is rerun), or "todo" (missing, interrupted,
    failed, or running elsewhere)."""
    m = Path(out_dir) / "manifest.json"
    if not m.exists():
        return "todo"
    try:
        man = read_manifest(out_dir)
    except (json.JSONDecodeError, OSError):
        return "todo"
    if man.get("status") == "running" and process_gone(man.get("process")):
        return "gone"
    if man.get("status") not in DONE or not steps_readable(out_dir):
        return "todo"
    if fingerprint and man.get("fingerprint") != fingerprint:
        return "stale"
    return "done"


def is_done(out_dir: str) -> bool:
    """Whether the run in ``out_dir`` ended (finished or filter-failed) with its table merged and readable."""
    m = Path(out_dir) / "manifest.json"
    if not m.exists():
        return False
    try:
        return read_manifest(out_dir).get("status") in DONE and steps_readable(out_dir)
    except (json.JSONDecodeError, OSError):
        return False
