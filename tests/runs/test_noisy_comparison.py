"""The built-in ``noisy-comparison`` study (issue 16's acceptance comparison): Example 1 with
noisy-range IOD for the default PGM, the EnKF and the iterated UKF on the same seeds, each
filter's custody with its Wilson interval side by side.

Run through a real process executor, cut to 2 seeds from a chosen first seed and to the first
pass (1.3 days, 2,000 IOD particles)."""
from __future__ import annotations

import csv
from importlib import resources

import pytest

from cistrack.results.store import read_manifest
from cistrack.studies.study import plan_runs, run_study
from cistrack.studies.report import report_study

SETTINGS = ["duration_days=1.3", "iod.n_particles=2000"]


def test_the_study_runs_the_default_pgm_enkf_and_iterated_ukf_on_noisy_range_over_100_seeds():
    text = (resources.files("cistrack.scenarios") / "studies" / "noisy-comparison.toml").read_text()
    assert "n_seeds = 100" in text
    _, specs, _ = plan_runs("noisy-comparison")
    assert {s.filter_label for s in specs} == {"pgm", "enkf", "ukf"} and {s.iod_label for s in specs} == {"noisy-range"}
    assert {s.scenario_name for s in specs} == {"example-1"}
    by_filter = {f: sorted(s.seed for s in specs if s.filter_label == f) for f in ("pgm", "enkf", "ukf")}
    assert by_filter["pgm"] == by_filter["enkf"] == by_filter["ukf"] and len(by_filter["pgm"]) == 100


def test_the_first_seed_and_the_number_of_seeds_are_settable():
    _, specs, _ = plan_runs("noisy-comparison", first_seed=5000, n_seeds=3)
    assert sorted({s.seed for s in specs}) == [5000, 5001, 5002] and len(specs) == 9
    assert sorted({s.seed for s in plan_runs("noisy-comparison", n_seeds=2)[1]}) == [1, 2]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("noisy") / "s"
    res = run_study("noisy-comparison", out_dir=out, workers=1, progress=False, settings=SETTINGS,
                    first_seed=1000, n_seeds=2)
    assert (res["completed"], res["failed"], res["total"]) == (6, 0, 6)
    return report_study("noisy-comparison", out_dir=out, settings=SETTINGS, first_seed=1000, n_seeds=2), out


def test_the_report_gives_each_filters_custody_with_its_wilson_interval_side_by_side(report):
    from scipy.stats import binomtest

    rep, out = report
    with open(out / "report" / "custody_by_filter.csv") as fh:
        (row,) = list(csv.DictReader(fh))
    assert (row["scenario"], row["iod"]) == ("example-1", "noisy-range")
    for r in rep["rows"]:
        kinds = [read_manifest(d)["summary"]["verdict"]["kind"] for d in (out / "runs").iterdir()
                 if f"__{r['filter']}__" in d.name]
        assert r["tracking_runs"] == kinds.count("tracking")
        ci = binomtest(r["custody_kept"], r["runs"]).proportion_ci(0.95, method="wilson")
        cell = (f"{r['custody_kept']}/2 = {r['custody_kept'] / 2:.2f} [{ci.low:.2f}-{ci.high:.2f}], "
                f"tracking {r['tracking_runs']}")
        assert row[f"{r['filter']} custody [Wilson 95 %]"] == cell
        assert f"{r['filter']} {cell}" in " ".join(rep["text"].split())  # the terminal text wraps at 120
    md = (out / "report" / "summary.md").read_text()
    assert "| scenario | iod | enkf | pgm | ukf |" in md


def test_the_runs_are_the_chosen_seeds(report):
    _, out = report
    assert sorted(d.name for d in (out / "runs").iterdir()) == sorted(
        f"example-1__{f}__noisy-range__seed{s}" for f in ("pgm", "enkf", "ukf") for s in (1000, 1001))


def test_the_command_line_takes_the_seeds_for_run_and_report(tmp_path, capsys):
    from cistrack.cli.main import main

    assert main(["study", "report", "noisy-comparison", "--out", str(tmp_path / "s"), "--first-seed", "7",
                 "--n-seeds", "1"]) == 2
    assert "none of its 3 runs has finished" in capsys.readouterr().err
