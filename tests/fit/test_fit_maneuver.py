"""cistrack fit on the observations of an object that maneuvered (issue 52, item 5): the burn is
found, reported in fit.json's ``maneuvers`` with its epoch and delta-v (within 3 sigma of the
truth), and the fit with it uses every observation; an object that did not maneuver gets none."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cistrack import units
from cistrack.fitting.from_observations import fit_files
from cistrack.runs.observation_files import write_observations

from .arc_campaigns import two_weeks
from .burn_campaigns import burned

pytestmark = pytest.mark.slow  # about a minute of CPU per fit


def _fit(tmp_path, dv_ms: float):
    b = burned(dv_ms)
    write_observations(tmp_path / "obs.psv", b.measurements, two_weeks().epoch, format="ades-psv")
    (one,) = fit_files([tmp_path / "obs.psv"], out=tmp_path / "fit")
    record = json.loads((one.directory / "fit.json").read_text())
    return b, one, record


def test_a_burn_of_0_3_m_s_is_reported_with_its_epoch_and_delta_v(tmp_path):
    b, one, record = _fit(tmp_path, 0.3)
    (m,) = record["maneuvers"]
    shift = float(b.measurements.times[0]) - float(one.run.context.measurements.times[0])  # the fit's time base
    t_true = float(b.t_burn - shift)
    assert abs(m["t_burn_days"] - float(units.tu_to_days(t_true))) <= 3 * m["t_burn_sigma_days"]
    assert abs(m["delta_v_ms"] - 0.3) <= 3 * m["delta_v_sigma_ms"]
    assert one.ok and one.result.n_rejected <= 2


def test_no_burn_is_reported_for_an_object_that_did_not_maneuver(tmp_path):
    _, one, record = _fit(tmp_path, 0.0)
    assert record["maneuvers"] == [] and one.ok
    assert np.isfinite(one.result.rms)
