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


MPC_LINES = ["     K26A01A  C2026 03 01.04167606 51 33.239-07 54 18.29                     705",
             "     K26A01A  C2026 03 01.05167606 51 35.239-07 54 10.29                     705",
             "     K26A01A  C2026 03 01.06167606 51 37.239-07 54 02.29                     705"]


def _mpc(tmp_path, lines):
    path = tmp_path / "both.obs"
    path.write_text("\n".join(lines) + "\n")
    return read_observations(path, EPOCH)


def test_a_line_with_a_number_and_a_provisional_designation_is_named_by_the_number(tmp_path):
    """Columns 1-5 and 6-12 had been joined into '00433K26A01A', a designation of neither (probe I6)."""
    ms = _mpc(tmp_path, ["00433" + line[5:] for line in MPC_LINES])
    assert ms.meta["object"] == "00433"


def test_lines_giving_the_provisional_designation_alone_are_the_numbered_objects_own(tmp_path):
    """One object's arc had been split into 'K26A01A' and '00433K26A01A' (probe I6)."""
    ms = _mpc(tmp_path, [MPC_LINES[0], "00433" + MPC_LINES[1][5:], MPC_LINES[2]])
    assert ms.meta["object"] == "00433" and len(ms) == 3
