"""The area-to-mass ratio estimated because it was asked for (fit.area_to_mass=solve) on an arc
that cannot determine it: the fit says so, and the export and sky predictions still work (their
sigma points of the ratio beyond what the dynamics allow had ended both in a parameter error)."""
from __future__ import annotations

import json

import pytest

from cistrack.cli.main import main

from .test_lov_solutions import NIGHT


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("forced")
    (d / "night.psv").write_text(NIGHT)
    assert main(["fit", str(d / "night.psv"), "--out", str(d / "fit"), "--quiet", "--set", "fit.area_to_mass=solve"]) == 0
    return d / "fit"


def test_the_fit_says_the_arc_does_not_determine_the_ratio_it_was_asked_for(fitted):
    amr = json.loads((fitted / "fit.json").read_text())["area_to_mass"]
    assert amr["estimated"] and "is not significant" in amr["decision"]
    assert "this arc does not determine it" in amr["decision"]


def test_its_export_is_written(fitted):
    assert main(["export", str(fitted), "--format", "oem", "--quiet"]) == 0
    assert (fitted / "estimate.oem").is_file()


def test_its_sky_predictions_are_written(fitted):
    assert main(["predict", str(fitted), "--site", "M22", "--quiet"]) == 0
    assert (fitted / "sky-M22.csv").is_file()
