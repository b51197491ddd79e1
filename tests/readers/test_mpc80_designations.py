"""The MPC 80-column writer writes the designation in columns 6-12 and refuses one it cannot
write so that reading gives it back: longer than 7 characters (it had cut '2025-010D' and
'2025-010E' both to '2025-01') or blank (it had written a file its reader refuses). Packed
numbers and provisional designations are read in the form ADES files give them, and a
provisional designation is written packed (probe N15: one object given in both formats had been
fitted as two, 'K26F01A' and '2026 FA1')."""
from __future__ import annotations

import pytest

from cistrack.fitting.observation_input import read_object_observations
from cistrack.plugin.registry import default_registry
from cistrack.plugins.readers.mpc_designations import pack_provisional, unpack_number, unpack_provisional

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
    assert ms.meta["object"] == "433"


def test_lines_giving_the_provisional_designation_alone_are_the_numbered_objects_own(tmp_path):
    """One object's arc had been split into 'K26A01A' and '00433K26A01A' (probe I6)."""
    ms = _mpc(tmp_path, [MPC_LINES[0], "00433" + MPC_LINES[1][5:], MPC_LINES[2]])
    assert ms.meta["object"] == "433" and len(ms) == 3


@pytest.mark.parametrize("packed, unpacked", [("00433", "433"), ("00001", "1"), ("A0433", "100433"),
                                              ("a0000", "360000"), ("z9999", "619999"), ("~0000", "620000"),
                                              ("~000z", "620061"), ("C1AMX", "C1AMX")])
def test_packed_numbers_read_as_the_mpc_documents_them(packed, unpacked):
    assert unpack_number(packed) == unpacked


@pytest.mark.parametrize("packed, unpacked", [("J95X00A", "1995 XA"), ("J95X01L", "1995 XL1"),
                                              ("J95F13B", "1995 FB13"), ("J98SA8Q", "1998 SQ108"),
                                              ("J98SC7V", "1998 SV127"), ("J98SG2S", "1998 SS162"),
                                              ("K99AJ3Z", "2099 AZ193"), ("K08Aa0A", "2008 AA360"),
                                              ("K07Tf8A", "2007 TA418"), ("K26F01A", "2026 FA1"),
                                              ("PLS2040", "2040 P-L"), ("T1S3138", "3138 T-1"),
                                              ("T3S4101", "4101 T-3"), ("C1AMXV2", "C1AMXV2"), ("cis0001", "cis0001")])
def test_packed_provisional_designations_read_as_the_mpc_documents_them(packed, unpacked):
    assert unpack_provisional(packed) == unpacked


@pytest.mark.parametrize("unpacked", ["1995 XA", "1998 SQ108", "2008 AA360", "2026 FA1", "2099 AZ193"])
def test_packing_a_provisional_designation_undoes_unpacking_it(unpacked):
    assert unpack_provisional(pack_provisional(unpacked)) == unpacked


def test_one_object_in_mpc_80_column_and_ades_files_is_one_object(tmp_path):
    ms = read_observations(DATA / "observations.psv", EPOCH)
    half = len(ms) // 2
    first, second = ms.subset(slice(0, half)), ms.subset(slice(half, len(ms)))
    first.meta["object"] = second.meta["object"] = "2026 FA1"
    write_observations(tmp_path / "early.obs", first, EPOCH)  # written packed, K26F01A
    write_observations(tmp_path / "late.psv", second, EPOCH, format="ades-psv")
    assert "K26F01A" in (tmp_path / "early.obs").read_text()
    objs = read_object_observations([tmp_path / "early.obs", tmp_path / "late.psv"], default_registry())
    assert [(o.designation, len(o.measurements)) for o in objs] == [("2026 FA1", len(ms))]
