"""`cistrack fit --set fit.arcs=each` end to end (issue 49, gap 3): every arc of a multi-arc file is
fitted on its own, into ``OUT/arc-<first date>``, and each is reported in the summary and recorded
in its own ``fit.json``.

The file: three arcs of the real stage 2025-010D cut from ``core/scenarios/real_data/2025-010D-dev.psv``
(its header and credits kept): the discovery tracklet of 2025-01-20 (4 exposures, W68), the two
nights of 2025-12-21/25 (12, P13) and 2026-04-11 to 04-17 (20, P13), more than 30 days apart from
one another (:data:`cistrack.fitting.arcs.LONG_GAP_DAYS`). Measured (2 shared cores, ~20 s): the
discovery tracklet is reported as one tracklet that determines no orbit (with its admissible
region); the December nights converge, poorly determined (2 sessions from one site, range 1-sigma
4,400 km; before the ranging's patient retry: "no seed tracklet gave an orbit that fits its
neighbours", its seed fit needing 84 iterations of 60); the April arc converges (20 of 20 used,
post-fit RMS 0.23"/0.27" at the reader's default 1"). The exit status is 3: not every arc gave an
orbit.
"""
from __future__ import annotations

import io
import json
import sys

import pytest

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path

DEV = builtin_scenario_path("real-data").parent / "real_data" / "2025-010D-dev.psv"
FAST = ["--set", "iod.n_particles=1000", "--set", "filter.n_particles=1000"]
ARCS = {"arc-2025-01-20": 4, "arc-2025-12-21": 12, "arc-2026-04-11": 20}


def _three_arcs(path) -> None:
    """The dev file's header, comments and block headers, with the observations of the three arcs."""
    keep = []
    for line in DEV.read_text().splitlines():
        if line.startswith(("#", "!", "trkSub")) or not line.strip():
            keep.append(line)
            continue
        t = line.split("|")[3]
        if t.startswith(("2025-01", "2025-12")) or "2026-04-11" <= t[:10] <= "2026-04-17":
            keep.append(line)
    path.write_text("\n".join(keep) + "\n")


@pytest.fixture(scope="module")
def each(tmp_path_factory):
    """(results directory, exit status, stdout) of `cistrack fit FILE --set fit.arcs=each`."""
    d = tmp_path_factory.mktemp("each")
    _three_arcs(d / "three-arcs.psv")
    buf = io.StringIO()
    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "stdout", buf)
    try:
        rc = main(["fit", str(d / "three-arcs.psv"), "--out", str(d / "out"), "--set", "fit.arcs=each", *FAST])
    finally:
        mp.undo()
    return d / "out", rc, buf.getvalue()


def test_each_arc_has_its_own_directory_and_record(each):
    out, rc, _ = each
    assert rc == 3                                          # not every arc gave an orbit
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == sorted(ARCS)
    for name, n in ARCS.items():
        rec = json.loads((out / name / "fit.json").read_text())
        assert rec["designation"] == "25010D" and rec["settings"]["options"]
        if "arc" in rec:                                   # the arc the fit ran on: this one only
            assert rec["arc"]["n_observations"] == n and rec["arc"]["first_utc"][:10] == name[4:]


def test_each_arc_is_reported_in_the_summary_in_time_order(each):
    out, _, text = each
    heads = [line for line in text.splitlines() if line.startswith("fit 25010D:")]
    assert len(heads) == 3
    where = [text.index(f"results in {out / name}") for name in ARCS]
    assert where == sorted(where)
    assert heads[0] == "fit 25010D: UNDETERMINED: one tracklet does not determine an orbit"
    assert heads[2].startswith("fit 25010D: converged")


def test_the_lone_discovery_tracklet_is_recorded_as_undetermined(each):
    rec = json.loads((each[0] / "arc-2025-01-20" / "fit.json").read_text())
    assert rec["converged"] is False and "state" not in rec
    assert rec["undetermined"]["tracklet"]["n_observations"] == 4
    assert rec["undetermined"]["tracklet"]["site"] == "W68"
    lo, hi = rec["undetermined"]["admissible_region"]["range_km"]
    assert lo < hi


def test_the_april_arc_is_fitted_on_its_own(each):
    rec = json.loads((each[0] / "arc-2026-04-11" / "fit.json").read_text())
    assert rec["converged"] is True
    assert rec["n_used"] + rec["n_rejected"] == 20 and rec["n_rejected"] <= 1
    assert rec["arc"]["first_utc"].startswith("2026-04-11") and rec["arc"]["last_utc"].startswith("2026-04-17")
    assert rec["determination"]["sentence"].startswith(("poorly determined", "well determined"))
    residuals = (each[0] / "arc-2026-04-11" / "residuals.csv").read_text().splitlines()
    assert len(residuals) == 1 + 20


def test_the_december_nights_are_fitted_and_called_poorly_determined(each):
    """Two tracklets four days apart from one site: an orbit, and the words that it is weak."""
    rec = json.loads((each[0] / "arc-2025-12-21" / "fit.json").read_text())
    assert rec["converged"] is True and rec["n_used"] + rec["n_rejected"] == 12
    assert rec["determination"]["sentence"].startswith("poorly determined")


@pytest.mark.parametrize("command", [["export"], ["predict", "--site", "568"]])
def test_export_or_predict_of_the_folder_of_each_arc_names_the_arc_folders(tmp_path, capsys, command):
    """The --out of fit.arcs=each had been refused as "not a cistrack run directory (no scenario.toml)"."""
    for name in ("arc-2026-03-01", "arc-2029-03-01"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "fit.json").write_text(json.dumps({"format": "cistrack-fit"}))
    assert main([command[0], str(tmp_path), *command[1:]]) == 2
    err = capsys.readouterr().err
    assert "holds one fit per arc (fit.arcs=each), one folder each (arc-2026-03-01, arc-2029-03-01)" in err
    assert f"e.g. {tmp_path / 'arc-2029-03-01'}" in err and "scenario.toml" not in err
