"""examples/real-data/check_fit.py refuses a survey set whose object made a burn: it flies the truth
from its first row, across the burn, and had reported every such fit as failing (probe J9)."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).parents[2] / "examples" / "real-data"


def test_check_fit_refuses_a_burned_set_naming_the_burn_and_the_script_that_handles_it(tmp_path):
    survey_set, fit = tmp_path / "set", tmp_path / "fit"
    survey_set.mkdir()
    fit.mkdir()
    (survey_set / "truth.csv").write_text("utc,x_km,y_km,z_km,vx_kms,vy_kms,vz_kms\n")
    (survey_set / "set.json").write_text(json.dumps({"burn": {"utc": "2026-08-31T05:51:42Z", "delta_v_ms": 0.5}}))
    (fit / "fit.json").write_text(json.dumps({"state_km": [0.0] * 6, "files": [str(survey_set / "observations.psv")]}))
    check = subprocess.run([sys.executable, str(EXAMPLES / "check_fit.py"), str(fit)], capture_output=True, text=True,
                           timeout=300)
    assert check.returncode != 0 and "Traceback" not in check.stderr
    assert "names a burn at 2026-08-31T05:51:42Z" in check.stderr and "does not handle burned sets" in check.stderr
    assert "examples/survey-sets/check_survey_fit.py" in check.stderr
