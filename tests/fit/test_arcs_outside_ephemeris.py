"""`cistrack fit` of a file where some arcs lie outside the years its dynamics can model (DE421's
1900 to 2052): those arcs are set aside like other far arcs, with a note saying which and why; only
an arc that is to be fitted and lies outside refuses the file (probe I4: one observation with its
year mistyped 1899 had refused the whole file, while the same typo dated 1901 was set aside)."""
from __future__ import annotations

import json

from cistrack.cli.main import main
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

SET = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"


def _with_dates(tmp_path, name: str, dates: dict[int, str]):
    """A copy of the real-data example (65 observations, 2026-03-01 to 03-06) with the dates of the
    observation rows numbered in ``dates`` (0 = the first) replaced."""
    lines = SET.read_text().splitlines()
    rows = [i for i, line in enumerate(lines) if "|2026-" in line]
    for k, when in dates.items():
        f = lines[rows[k]].split("|")
        f[3] = when
        lines[rows[k]] = "|".join(f)
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_one_observation_dated_before_the_ephemeris_is_set_aside_and_the_rest_fitted(tmp_path, capsys):
    typo = _with_dates(tmp_path, "y1899.psv", {2: "1899-03-01T23:58:59.988305Z"})
    assert main(["fit", str(typo), "--out", str(tmp_path / "out")]) == 0
    out = " ".join(capsys.readouterr().out.split())
    note = ("1 observation(s) in 1 arc(s) more than 30 days from the others (the first from site 809 on 1899-03-01) "
            "are not fitted: outside the years the fit can model (dynamics 'ephemeris': the epoch must lie within "
            "DE421's span (years 1900 to 2052))")
    assert note in out
    record = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert any(note in m for m in record["messages"]) and "64 observations" in out


def test_the_latest_arc_outside_the_ephemeris_refuses_the_file_with_its_own_dates(tmp_path, capsys):
    later = tmp_path / "y2060.psv"
    later.write_text(SET.read_text().replace("|2026-03-05", "|2060-03-05").replace("|2026-03-06", "|2060-03-06"))
    assert main(["fit", str(later), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "run from 2060-03-05" in err and "which the fit cannot model" in err and "years 1900 to 2052" in err


def test_one_fit_over_every_arc_refuses_observations_that_end_past_the_ephemeris(tmp_path, capsys):
    """fit.arcs=all with the last row dated 2060: the fit had run over 34 years, past DE421's 2052
    (probe K7); its start alone lies inside."""
    typo = _with_dates(tmp_path, "y2060.psv", {64: "2060-03-06T23:58:59.988305Z"})
    code = main(["fit", str(typo), "--out", str(tmp_path / "out"), "--set", "fit.arcs=all", "--quiet"])
    err = " ".join(capsys.readouterr().err.split())
    assert code == 2 and "to 2060-03-06" in err and "which the fit cannot model" in err and "2052" in err, err
