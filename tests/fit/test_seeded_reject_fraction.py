"""``--set fit.max_reject_fraction`` applies to the least squares started from the ranging IOD's
orbit, and fit.json records the share applied. That fit had capped the setting at 0.1 without a
word, while its note named the setting as the way to reject more, and fit.json recorded the
setting (0.5, or the value given) beside the 0.1 applied (probe I5)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.fitting.from_observations import SEEDED_REJECT_FRACTION, fit_choices, seeded_reject_fraction

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "survey-sets"


def test_the_least_squares_from_the_iods_orbit_keeps_to_a_fraction_that_is_set():
    assert seeded_reject_fraction(fit_choices({"max_reject_fraction": 0.2})) == 0.2


def test_the_least_squares_from_the_iods_orbit_caps_the_default_fraction():
    assert seeded_reject_fraction(fit_choices({})) == SEEDED_REJECT_FRACTION


@pytest.fixture(scope="module")
def shifted_set(tmp_path_factory) -> Path:
    """nrho-s1100 (a maneuver-free survey set with one genuine outlier) with one 3-exposure tracklet
    moved 0.3 degrees in RA: 4 of 32 observations to reject, more than 0.1 of them."""
    sys.path.insert(0, str(EXAMPLES))
    from make_survey_sets import make

    d = tmp_path_factory.mktemp("sets")
    make(d / "nrho", "nrho", seed=1100)
    lines = (d / "nrho" / "observations.psv").read_text().splitlines()
    head, data = lines[:2], lines[2:]  # '# version=2022', the field names
    for i in (14, 15, 16):  # the tracklet of 2026-10-29
        f = data[i].split("|")
        f[4] = repr(float(f[4]) + 0.3)  # ra
        data[i] = "|".join(f)
    path = d / "shifted.psv"
    path.write_text("\n".join(head + data) + "\n")
    return path


@pytest.mark.parametrize("setting, applied, ok", [(None, SEEDED_REJECT_FRACTION, False), (0.2, 0.2, True)])
def test_fit_json_records_the_rejected_share_applied_and_a_raised_one_rejects_the_tracklet(
        shifted_set, tmp_path, setting, applied, ok):
    out = tmp_path / "fit"
    extra = [] if setting is None else ["--set", f"fit.max_reject_fraction={setting}"]
    assert main(["fit", str(shifted_set), "--out", str(out), "--quiet", *extra]) == (0 if ok else 3)
    record = json.loads((out / "fit.json").read_text())
    assert record["settings"]["options"]["max_reject_fraction"] == applied
    assert record["converged"] is ok


def test_an_outlier_kept_by_the_cap_is_named_as_what_pulls_the_fit_not_a_maneuver(shifted_set, tmp_path):
    """The genuine outlier kept by the 0.1 cap pulled the orbit off the first night, which the fit
    had reported as "an object that maneuvered"."""
    assert main(["fit", str(shifted_set), "--out", str(tmp_path / "fit"), "--quiet"]) == 3
    messages = json.loads((tmp_path / "fit" / "fit.json").read_text())["messages"]
    note = next(m for m in messages if m.startswith("not a clean fit"))
    assert "1 observation above the chi-square threshold" in note and "is kept because fit.max_reject_fraction" in note
    assert f"({SEEDED_REJECT_FRACTION:g} applied)" in note and "it may be what pulls the fit" in note
    assert "maneuvered" not in note
