"""A TDM metadata keyword, or one of cistrack's comments (a sigma, a site), given twice in one
META block is refused naming both lines (each had silently taken the last value)."""
from __future__ import annotations

import re

import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"
META = "TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = X\nANGLE_TYPE = AZEL\n"
DATA = "DATA_START\nANGLE_1 = 2026-03-01T0{h}:00:00 10.5\nANGLE_2 = 2026-03-01T0{h}:00:00 20.5\nDATA_STOP\n"


def _tdm(tmp_path, extra: str):
    path = tmp_path / "repeat.tdm"
    path.write_text(HEAD + "META_START\n" + META + extra + "META_STOP\n" + DATA.format(h=1))
    return path


@pytest.mark.parametrize("extra, keyword", [("PARTICIPANT_1 = 711\n", "PARTICIPANT_1"),
                                            ("TIME_SYSTEM = UTC\n", "TIME_SYSTEM")])
def test_a_keyword_given_twice_in_one_block_is_refused_naming_both_lines(tmp_path, extra, keyword):
    path = _tdm(tmp_path, extra)
    first = 5 if keyword == "TIME_SYSTEM" else 6
    with pytest.raises(MeasurementError, match=rf"{re.escape(str(path))}, line 9, field {keyword}: given again: "
                                               rf"line {first} of this metadata block \(from line 4\) gives it already"):
        read_observations(path, EPOCH)


@pytest.mark.parametrize("extra, what", [
    ("COMMENT cistrack sigma_arcsec ANGLE_1=1 ANGLE_2=1\nCOMMENT cistrack sigma_arcsec ANGLE_1=100 ANGLE_2=100\n",
     "cistrack sigma_arcsec"),
    ("COMMENT cistrack site S latitude_deg=10 longitude_deg=20 height_m=0\n"
     "COMMENT cistrack site S latitude_deg=11 longitude_deg=20 height_m=0\n", "cistrack site S")])
def test_a_cistrack_comment_given_twice_in_one_block_is_refused_naming_both_lines(tmp_path, extra, what):
    path = _tdm(tmp_path, extra)
    with pytest.raises(MeasurementError, match=rf"{re.escape(str(path))}, line 10, field COMMENT {what}: given "
                                               r"again: line 9 of this metadata block \(from line 4\) gives it already"):
        read_observations(path, EPOCH)


def test_a_header_keyword_given_twice_is_refused_naming_both_lines(tmp_path):
    path = tmp_path / "header.tdm"
    path.write_text(HEAD + "ORIGINATOR = someone else\nMETA_START\n" + META + "META_STOP\n" + DATA.format(h=1))
    with pytest.raises(MeasurementError, match=rf"{re.escape(str(path))}, line 4, field ORIGINATOR: given again: "
                                               r"line 3 of the header gives it already"):
        read_observations(path, EPOCH)
