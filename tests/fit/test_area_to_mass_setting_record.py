"""fit.json records the area-to-mass setting the fit ran under, "off" included: a fit told
``fit.area_to_mass=off`` had written no setting at all, the same record as one that never heard of
the option (probe K3)."""
from __future__ import annotations

import json

from cistrack.cli.main import main

from .test_lov_solutions import NIGHT


def test_a_fit_told_not_to_estimate_the_ratio_records_off(tmp_path):
    (tmp_path / "night.psv").write_text(NIGHT)
    assert main(["fit", str(tmp_path / "night.psv"), "--out", str(tmp_path / "fit"), "--quiet",
                 "--set", "fit.area_to_mass=off"]) == 0
    record = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert record["settings"]["options"]["area_to_mass"] == "off"
    assert record.get("area_to_mass") is None
