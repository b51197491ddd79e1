"""Residuals that no burn explains are never a clean fit with maneuvers: a Dec bias after a date,
a file mostly of outliers, a lone tracklet of exactly two hours."""
from __future__ import annotations

import json
import random

import pytest

from cistrack.cli.main import main
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

OBSERVATIONS = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"


def _edited(path, edit) -> object:
    """The shipped example with ``edit(fields)`` applied to each observation row (ADES PSV fields)."""
    out = []
    for line in OBSERVATIONS.read_text().splitlines():
        if line.startswith(("#", "trkSub")) or "|" not in line:
            out.append(line)
            continue
        f = line.split("|")
        edit(f)
        out.append("|".join(f))
    path.write_text("\n".join(out) + "\n")
    return path


def _shift_dec_after(date: str, arcsec: float):
    def edit(f):
        if f[3] >= date:
            f[5] = repr(float(f[5]) + arcsec / 3600.0)
    return edit


def _outliers(share: float, seed: int):
    rng = random.Random(seed)

    def edit(f):
        if rng.random() < share:
            for k in (4, 5):
                f[k] = repr(float(f[k]) + rng.choice([-1, 1]) * rng.uniform(20.0, 60.0) / 3600.0)
    return edit


@pytest.mark.slow
@pytest.mark.parametrize("name, edit", [("biased", _shift_dec_after("2026-03-05", 10.0)),
                                        ("outliers", _outliers(0.6, 1))])
def test_residuals_no_burn_explains_are_not_a_clean_fit_with_maneuvers(tmp_path, capsys, name, edit):
    obs = _edited(tmp_path / f"{name}.psv", edit)
    assert main(["fit", str(obs), "--out", str(tmp_path / name), "--quiet"]) == 3
    record = json.loads((tmp_path / name / "fit.json").read_text())
    assert record["converged"] is False and not record.get("maneuvers")
    assert any("not a clean fit" in m for m in record["messages"])


def test_a_lone_tracklet_of_exactly_two_hours_determines_no_orbit(tmp_path, capsys):
    header = "# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
    rows = "".join(f"cis0001|CCD|711|2026-04-13T0{h}:00:00.000000Z|{200 + k}.0|-5.0{k}|1.0|1.0|Gaia3\n"
                   for k, h in enumerate((3, 4, 5)))
    (tmp_path / "lone.psv").write_text(header + rows)
    assert main(["fit", str(tmp_path / "lone.psv"), "--out", str(tmp_path / "f"), "--quiet"]) == 3
    assert "one tracklet does not determine an orbit" in capsys.readouterr().err


@pytest.mark.slow
def test_a_fit_whose_latest_observations_are_rejected_says_how_far_its_epoch_lies_beyond_the_data(tmp_path):
    text = OBSERVATIONS.read_text()
    late = "".join(f"cis0001|CCD|711|2026-03-13T0{h}:00:00.000000Z|{200 + k}.0|-5.0{k}|1.0|1.0|Gaia3\n"
                   for k, h in enumerate((3, 4, 5)))  # three observations far off the orbit
    obs = tmp_path / "late.psv"
    obs.write_text(text + late)
    assert main(["fit", str(obs), "--out", str(tmp_path / "f"), "--quiet"]) in (0, 3)
    record = json.loads((tmp_path / "f" / "fit.json").read_text())
    assert any("days after the last observation it used" in m for m in record["messages"])
