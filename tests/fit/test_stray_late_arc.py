"""`cistrack fit` of an object whose latest arc no orbit determination starts from (probe N2).

A stray pair of observations filed under an object's designation 50 days after its good arc
(two pairs of two exposures, two days apart: no tracklet of three, no first pass of eight) had
made the default fit (``fit.arcs=latest``) run on those four alone and fail ("no tracklet has 3
observations ...; lower min_tracklet"), the earlier arc never mentioned. The fit is now of the
latest arc that can be fitted, and a note names the observations left out and ``fit.arcs=each``.
"""
from __future__ import annotations

import json
from pathlib import Path

from cistrack.cli.main import main

SHIPPED = Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv"
STRAY_TIMES = ("2026-04-25T03:00:00Z", "2026-04-25T03:10:00Z", "2026-04-27T03:00:00Z", "2026-04-27T03:10:00Z")


def _rows() -> tuple[str, list[str], list[str]]:
    """(header, the shipped file's rows, four stray rows: the first rows' angles at new times)."""
    lines = [r for r in SHIPPED.read_text().splitlines() if r and not r.startswith("#")]
    header, rows = lines[0], lines[1:]
    stray = []
    for src, t in zip(rows[:4], STRAY_TIMES):
        f = src.split("|")
        f[3] = t
        stray.append("|".join(f))
    return header, rows, stray


def test_a_stray_late_arc_leaves_the_earlier_arc_fitted_and_named(tmp_path, capsys):
    header, rows, stray = _rows()
    f = tmp_path / "with_stray.psv"
    f.write_text("\n".join([header, *rows, *stray]) + "\n")
    rc = main(["fit", str(f), "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    rec = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert rc == 0 and rec["converged"] is True
    assert rec["n_used"] + rec["n_rejected"] == len(rows)            # the earlier arc, all of it
    note = next(m for m in rec["messages"] if "later observation(s)" in m)
    assert "4 later observation(s)" in note and "2026-04-25 to 2026-04-27" in note
    assert "fit.arcs=each" in note and "lower min_tracklet" not in note
    assert "4 later observation(s)" in out
