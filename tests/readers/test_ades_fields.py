"""ADES fields that say what a record is or how its errors are correlated: ``mode`` (radar records
are left out, as the XML reader leaves out ``<radar>``; other modes are read with a warning) and
``rmsCorr`` (a correlation, in [-1, 1])."""
from __future__ import annotations

import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|rmsCorr|astCat\n"


def _psv(tmp_path, *rows: tuple[str, str]):
    """A PSV file of one row per (mode, rmsCorr), an hour apart at MPC 711."""
    body = "".join(f"X|{mode}|711|2026-03-01T{2 + k:02d}:00:00Z|10|5|0.5|0.5|{corr}|Gaia3\n"
                   for k, (mode, corr) in enumerate(rows))
    path = tmp_path / "fields.psv"
    path.write_text(HEAD + body)
    return path


def _xml(tmp_path, mode: str, corr: str = ""):
    one = (f"<optical>\n<trkSub>X</trkSub>\n<mode>{mode}</mode>\n<stn>711</stn>\n<obsTime>2026-03-01T0{{h}}:00:00Z"
           f"</obsTime>\n<ra>10</ra>\n<dec>5</dec>\n<rmsCorr>{corr}</rmsCorr>\n</optical>\n")
    path = tmp_path / "fields.xml"
    path.write_text('<ades version="2022"><obsBlock><obsData>\n' + one.format(h=2) + one.format(h=3).replace(
        f"<mode>{mode}</mode>", "<mode>CCD</mode>") + "</obsData></obsBlock></ades>\n")
    return path


# -- rmsCorr ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("corr", ["-1", "0", "0.35", "1"])
def test_a_correlation_within_minus_one_and_one_is_read(tmp_path, corr):
    assert len(read_observations(_psv(tmp_path, ("CCD", corr), ("CCD", "")), EPOCH)) == 2


@pytest.mark.parametrize("corr", ["1.5", "-2", "nan", "inf", "strong"])
def test_a_correlation_outside_minus_one_and_one_is_refused_naming_file_line_and_value(tmp_path, corr):
    with pytest.raises(MeasurementError, match=rf"fields\.psv, line 4, field rmsCorr: '{corr}': a correlation must "
                                               r"be a number in \[-1, 1\]"):
        read_observations(_psv(tmp_path, ("CCD", "0"), ("CCD", corr)), EPOCH)


def test_the_xml_reader_refuses_it_the_same_way(tmp_path):
    with pytest.raises(MeasurementError, match=r"fields\.xml, line 9, field rmsCorr: '3'"):
        read_observations(_xml(tmp_path, "CCD", "3"), EPOCH)


# -- mode ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", ["CCD", "CMO", "VID", "PHO", "UNK", ""])
def test_optical_modes_and_no_mode_are_read(tmp_path, mode):
    assert len(read_observations(_psv(tmp_path, (mode, ""), ("CCD", "")), EPOCH)) == 2


def test_a_radar_row_beside_optical_ones_is_left_out_and_said(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_psv(tmp_path, ("RAD", ""), ("CCD", ""), ("CCD", "")), EPOCH)
    assert len(ms) == 2
    assert "fields.psv: 1 mode RAD records are not read (cistrack reads optical astrometry only)" in caplog.text


def test_a_file_of_radar_rows_only_is_refused_saying_optical_astrometry_is_read(tmp_path):
    with pytest.raises(MeasurementError, match=r"fields\.psv, line 1, field \(observations\): the file holds 2 mode "
                                               r"RAD records and no optical one"):
        read_observations(_psv(tmp_path, ("RAD", ""), ("RAD", "")), EPOCH)


def test_the_xml_reader_leaves_out_a_radar_optical_record_the_same_way(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_xml(tmp_path, "RAD"), EPOCH)
    assert len(ms) == 1 and "1 mode RAD records are not read" in caplog.text


@pytest.mark.parametrize("mode", ["radar", "XYZ"])
def test_a_mode_that_is_no_known_optical_one_is_read_with_a_warning_naming_file_and_line(tmp_path, mode, caplog):
    """ADES may add optical modes; a file using one is not refused, but the warning says the rows are
    read as optical RA/Dec."""
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_psv(tmp_path, (mode, ""), ("CCD", "")), EPOCH)
    assert len(ms) == 2
    assert f"fields.psv: line 3: mode '{mode}' is not an optical mode cistrack knows" in caplog.text


def test_occultation_astrometry_is_an_optical_mode(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        assert len(read_observations(_psv(tmp_path, ("OCC", ""), ("CCD", "")), EPOCH)) == 2
    assert "not an optical mode" not in caplog.text


# -- obsTime ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("when, why", [("2026-02-30T00:00:00Z", "2026-02-30 is not a date: February has 28 days in 2026"),
                                       ("2026-13-01T00:00:00Z", "2026-13-01 is not a date: there is no month 13")])
def test_a_well_formed_date_that_does_not_exist_is_said_so_quoting_the_value_once(tmp_path, when, why):
    path = _psv(tmp_path, ("CCD", "0"), ("CCD", "0"))
    path.write_text(path.read_text().replace("2026-03-01T03:00:00Z", when))
    with pytest.raises(MeasurementError) as info:
        read_observations(path, EPOCH)
    assert f"line 4, field obsTime: '{when}': {why}" in str(info.value) and str(info.value).count(when) == 1
