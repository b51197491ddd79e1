"""Lines end at LF, CR LF or CR only: a comment holding a form feed, U+2028, U+0085 or another
character that str.splitlines also breaks at stays one comment line (it had turned the rest of
the comment into a data or header line, and put the later line numbers off)."""
from __future__ import annotations

import re

import pytest

from cistrack.errors import MeasurementError
from cistrack.interfaces.reader import split_lines
from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
BREAKERS = ["\u2028", "\x85", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\u2029"]
PSV = ("# version=2022\n# comment{c}trkSub|stn|obsTime|ra|dec\ntrkSub|stn|obsTime|ra|dec\n"
       "X|705|2026-03-01T01:00:00Z|10|5\nX|705|2026-03-01T02:00:00Z|10|95\n")
MPC = ("# note{c}     K26A01A  C2026 03 01.04167606 51 33.239-07 54 18.29                     705\n"
       "     K26A01A  C2026 03 01.08333306 51 33.239-07 54 18.29                     ZZ9\n")
TDM = ("CCSDS_TDM_VERS = 2.0\nCOMMENT made by hand{c}ORIGINATOR = nobody\nCREATION_DATE = 2026-03-01T00:00:00\n"
       "META_START\nTIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nANGLE_TYPE = AZEL\nMETA_STOP\nDATA_START\n"
       "ANGLE_1 = 2026-03-01T01:00:00 10.5\nANGLE_2 = 2026-03-01T01:00:00 95\nDATA_STOP\n")
CSV = ("# comment{c}time_utc,colour\ntime_utc,azimuth_deg,elevation_deg,site\n2026-03-01T01:00:00Z,10.5,20.5,705\n"
       "2026-03-01T02:00:00Z,10.5,95,705\n")


def test_split_lines_breaks_at_lf_cr_lf_and_cr_only():
    assert split_lines("a\u2028b\x0cc\r\nd\re\nf\n") == ["a\u2028b\x0cc", "d", "e", "f"]


@pytest.mark.parametrize("c", BREAKERS, ids=[repr(c) for c in BREAKERS])
@pytest.mark.parametrize("text, suffix, line, field", [(PSV, ".psv", 5, "dec"), (MPC, ".obs", 2, "observatory code"),
                                                       (TDM, ".tdm", 11, "ANGLE_2 value"), (CSV, ".csv", 4, "elevation")],
                         ids=["ades-psv", "mpc80", "tdm", "csv"])
def test_a_comment_holding_another_line_separator_stays_one_line(tmp_path, c, text, suffix, line, field):
    path = tmp_path / f"comment{suffix}"
    path.write_text(text.format(c=c), encoding="utf-8")
    with pytest.raises(MeasurementError) as info:
        read_observations(path, EPOCH)
    assert re.search(rf"^{re.escape(str(path))}(, |: .*\n  )line {line}\b.*{field}", str(info.value)), str(info.value)
