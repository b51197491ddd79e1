"""The identity of a run: a hash of its resolved scenario, its seed and its input files.

Stored in each run's manifest (``fingerprint``); a study compares it with the fingerprint of the
run it would make now and reruns a finished run whose scenario, seed or measurement file changed,
instead of reporting stale numbers.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

__all__ = ["scenario_fingerprint", "tables_as_run"]


def _file_digest(path: Path) -> str:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        return f"unreadable: {exc.strerror}"
    return h.hexdigest()


def tables_as_run(raw: dict[str, Any], seed: int) -> dict[str, Any]:
    """The scenario tables ``raw`` with the ``seed`` actually run (``--seed``, a study's seed) in
    place of the file's: what a run records as its ``scenario.toml``, so that running that file
    again reproduces the run. ``raw`` itself when the file's seed (0 when not given) is that seed."""
    return raw if raw.get("seed", 0) == int(seed) else {**raw, "seed": int(seed)}


def scenario_fingerprint(scenario: Any, seed: int) -> str:
    """sha256 (hex, 16 characters) of the scenario's resolved tables as run (after overrides, with
    the seed run: :func:`tables_as_run`), the seed and the content of its measurement file, if any."""
    data = {"scenario": tables_as_run(scenario.raw, seed), "seed": int(seed)}
    meas = getattr(scenario, "measurements_file", None)
    if meas is not None:
        data["measurements_sha256"] = _file_digest(Path(meas))
    text = json.dumps(data, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]
