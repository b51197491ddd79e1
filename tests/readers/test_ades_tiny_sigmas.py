"""ADES rmsRA / rmsDec (and CSV sigma columns, TDM sigma comments) below 1 milliarcsecond (no astrometry is finer; 0.0003 is 1 arcsec written
in degrees) are used as given, with a warning naming the file, the line and the field and asking
whether they are degrees (they had been taken silently, and the fit then failed far from the data)."""
from __future__ import annotations

import re

import pytest

from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "# version=2022\ntrkSub|stn|obsTime|ra|dec|rmsRA|rmsDec\n"


def _psv(tmp_path, rms_ra: str, rms_dec: str):
    path = tmp_path / "rms.psv"
    path.write_text(HEAD + f"X|809|2026-03-01T01:00:00Z|10|5|1.0|1.0\nX|809|2026-03-01T02:00:00Z|10|5|{rms_ra}|{rms_dec}\n")
    return path


def _xml(tmp_path, rms_ra: str, rms_dec: str):
    path = tmp_path / "rms.xml"
    path.write_text('<ades version="2022"><obsBlock><obsData>\n<optical><trkSub>X</trkSub><stn>809</stn>'
                    f"<obsTime>2026-03-01T01:00:00Z</obsTime><ra>10</ra><dec>5</dec><rmsRA>{rms_ra}</rmsRA>"
                    f"<rmsDec>{rms_dec}</rmsDec></optical>\n</obsData></obsBlock></ades>\n")
    return path


@pytest.mark.parametrize("rms, field, line", [(("0.0003", "1.0"), "rmsRA", 4), (("1.0", "0.0003"), "rmsDec", 4)])
def test_an_uncertainty_below_a_milliarcsecond_is_said_naming_file_line_and_field(tmp_path, caplog, rms, field, line):
    path = _psv(tmp_path, *rms)
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(path, EPOCH)
    assert re.search(rf"{re.escape(str(path))}, line {line}: field {field}: 1 observations state an uncertainty below "
                     rf"1 milliarcsecond \(this one 0\.0003 arcsec\); ADES {field} is in arcseconds: are these degrees\?",
                     caplog.text), caplog.text


def test_the_xml_reader_says_so_too(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(_xml(tmp_path, "0.0003", "0.0003"), EPOCH)
    assert "field rmsDec: 1 observations state an uncertainty below 1 milliarcsecond" in caplog.text


def test_the_csv_reader_says_so_for_its_sigma_columns(tmp_path, caplog):
    path = tmp_path / "azel.csv"
    path.write_text("time_utc,azimuth_deg,elevation_deg,sigma_azimuth_arcsec,sigma_elevation_arcsec\n"
                    "2026-03-01T01:00:00Z,100.0,30.0,1.5,0.0004\n2026-03-01T02:00:00Z,101.0,31.0,1.5,1.5\n")
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(path, EPOCH)
    assert len(ms) == 2
    assert (f"{path}: column sigma_elevation_arcsec: 1 rows state an uncertainty below 1 milliarcsecond (the first "
            "0.0004 arcsec)") in caplog.text and "sigma_azimuth_arcsec" not in caplog.text


def test_the_tdm_reader_says_so_for_a_sigma_comment_once_per_file(tmp_path, caplog):
    head = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"
    seg = ("META_START\nCOMMENT cistrack sigma_arcsec ANGLE_1={s} ANGLE_2={s}\nTIME_SYSTEM = UTC\n"
           "PARTICIPANT_1 = 705\nPARTICIPANT_2 = X\nANGLE_TYPE = AZEL\nMETA_STOP\nDATA_START\n"
           "ANGLE_1 = 2026-03-01T0{h}:00:00 10.5\nANGLE_2 = 2026-03-01T0{h}:00:00 20.5\nDATA_STOP\n")
    path = tmp_path / "tiny.tdm"
    path.write_text(head + seg.format(s="1.5", h=1) + seg.format(s="0.0004", h=2) + seg.format(s="0.0004", h=3))
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(path, EPOCH)
    assert len(ms) == 3
    assert caplog.text.count("below 1 milliarcsecond") == 1
    assert (f"{path}, line 16: COMMENT cistrack sigma_arcsec: 2 segments state an uncertainty below 1 "
            "milliarcsecond (this one 0.0004 arcsec)") in caplog.text
