"""The MPC 80-column writer writes the designation in columns 6-12 and refuses one it cannot
write so that reading gives it back: longer than 7 characters (it had cut '2025-010D' and
'2025-010E' both to '2025-01') or blank (it had written a file its reader refuses)."""
from __future__ import annotations

import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations, write_observations
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
EPOCH = "2026-03-01T00:00:00Z"


def _write(tmp_path, designation: str):
    ms = read_observations(DATA / "observations.psv", EPOCH)
    ms.meta["object"] = designation
    write_observations(tmp_path / "out.obs", ms, EPOCH)


def test_a_designation_longer_than_the_columns_is_refused_naming_it_and_the_limit(tmp_path):
    with pytest.raises(MeasurementError, match=r"out\.obs: designation '2025-010D' has 9 characters; the MPC "
                                               r"designation field \(columns 6-12\) holds 7"):
        _write(tmp_path, "2025-010D")


def test_nothing_is_written_for_a_designation_that_does_not_fit(tmp_path):
    with pytest.raises(MeasurementError):
        _write(tmp_path, "2025-010E")
    assert not (tmp_path / "out.obs").exists()


@pytest.mark.parametrize("blank", ["", "   "])
def test_a_blank_designation_is_refused_when_writing(tmp_path, blank):
    with pytest.raises(MeasurementError, match=r"out\.obs: designation '\s*' is blank"):
        _write(tmp_path, blank)
