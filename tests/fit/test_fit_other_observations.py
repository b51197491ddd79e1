"""A fit of other observations under the same designation does not silently replace an earlier fit
(probe N6).

A ``trkSub`` is assigned by the observer and reused: two objects, two seasons apart, both named
``dro``, fitted one after the other into the same ``--out``, and the second replaced the first
with no word. A refit (observations in common with the earlier fit) still replaces it; one that
shares no observation is refused without ``--overwrite``, naming the earlier fit's files and dates.
Real fits of the shipped campaign: its first two nights, then its later nights alone."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from cistrack.cli.main import main

SHIPPED = Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv"


def _file(tmp_path: Path, name: str, keep) -> Path:
    lines = [r for r in SHIPPED.read_text().splitlines() if r and not r.startswith("#")]
    path = tmp_path / name
    path.write_text("\n".join([lines[0], *[r for r in lines[1:] if keep(r.split("|")[3])]]) + "\n")
    return path


@pytest.fixture()
def first_fit(tmp_path):
    early = _file(tmp_path, "early.psv", lambda t: t < "2026-03-03")
    out = tmp_path / "out"
    assert main(["fit", str(early), "--out", str(out)]) in (0, 3)
    return early, out


def test_a_fit_of_other_observations_under_the_same_name_is_refused(first_fit, tmp_path, capsys):
    early, out = first_fit
    late = _file(tmp_path, "late.psv", lambda t: t >= "2026-03-04")
    capsys.readouterr()
    assert main(["fit", str(late), "--out", str(out)]) != 0
    err = capsys.readouterr().err
    assert f"holds an earlier fit of 'cis0001' of other observations ({early}: 25 observations from 2026-03-01" in err
    assert "--overwrite" in err
    assert json.loads((out / "fit.json").read_text())["files"] == [str(early)]     # left as it was


def test_a_refit_with_the_same_observations_replaces_the_earlier_fit(first_fit, capsys):
    early, out = first_fit
    assert main(["fit", str(early), "--out", str(out)]) in (0, 3)
    assert "other observations" not in capsys.readouterr().err
