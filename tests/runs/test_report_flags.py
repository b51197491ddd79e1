"""Every run of a study that did not track (not-converged, lost, diverged with degenerate weights
or a collapsed belief, filter-failed) is flagged with its verdict and reason in the terminal text,
the Markdown and runs.csv (issue 16: "every diverged, degenerate or unconverged run in
filter-comparison is flagged with its reason").

Real short runs: the quick scenario's first pass (1.4 days) with the PGM (a cloud still ~200 km
wide: not-converged) and the bootstrap particle filter (weights degenerate: diverged)."""
from __future__ import annotations

import concurrent.futures as cf
import csv

import pytest

from cistrack.results.store import read_manifest
from cistrack.studies.study import run_study
from cistrack.studies.report import report_study

STUDY = """
name = "flags"
scenarios = ["quick"]
filters = [{ name = "pgm", n_particles = 300, n_components = 2 }, { name = "sir", n_particles = 300 }]
iod = [{ name = "noisy-range", n_particles = 300 }]
seeds = [1, 2]
[overrides]
duration_days = 1.4
"""


def _flat(text: str) -> str:
    """The text with its line wrapping undone (the terminal report wraps at 120 columns)."""
    return " ".join(text.split())


@pytest.fixture(scope="module")
def flagged(tmp_path_factory):
    d = tmp_path_factory.mktemp("flags")
    (d / "flags.toml").write_text(STUDY)
    out = d / "out"
    run_study(d / "flags.toml", out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False)
    rep = report_study(d / "flags.toml", out_dir=out)
    verdicts = {p.name: read_manifest(p)["summary"]["verdict"] for p in sorted((out / "runs").iterdir())}
    return rep, out, verdicts


def test_the_short_runs_include_a_diverged_and_a_not_converged_run(flagged):
    _, _, verdicts = flagged
    kinds = {v["kind"] for v in verdicts.values()}
    assert {"diverged", "not-converged"} <= kinds, verdicts


def test_every_run_that_did_not_track_is_in_the_terminal_text_with_its_reason(flagged):
    rep, _, verdicts = flagged
    for run_id, v in verdicts.items():
        line = f"- {run_id} ("
        if v["kind"] == "tracking":
            assert _flat(line) not in _flat(rep["text"])
        else:
            assert _flat(line) in _flat(rep["text"]) and _flat(f": {v['kind']}: {v['reason']}") in _flat(rep["text"])


def test_every_run_that_did_not_track_is_in_the_markdown_with_its_reason(flagged):
    _, out, verdicts = flagged
    md = (out / "report" / "summary.md").read_text()
    for run_id, v in verdicts.items():
        if v["kind"] != "tracking":
            assert any(ln.startswith(f"- {run_id} (") and f": {v['kind']}: {v['reason']}" in ln for ln in md.splitlines())


def test_runs_csv_holds_every_runs_verdict_and_reason(flagged):
    _, out, verdicts = flagged
    with open(out / "report" / "runs.csv") as fh:
        rows = {r["run_id"]: r for r in csv.DictReader(fh)}
    assert set(rows) == set(verdicts)
    for run_id, v in verdicts.items():
        assert (rows[run_id]["verdict"], rows[run_id]["reason"]) == (v["kind"], v["reason"])


def test_the_degenerate_weights_reason_reaches_the_report(flagged):
    rep, _, verdicts = flagged
    sir = [v for k, v in verdicts.items() if "__sir__" in k]
    assert sir and all(v["kind"] == "diverged" and v["reason"].startswith("degenerate weights") for v in sir)
    assert _flat(rep["text"]).count("degenerate weights (effective sample size") == len(sir)
