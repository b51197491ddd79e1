"""Every reader accepts a file that starts with a UTF-8 byte-order mark, refuses numbers written
with digits grouped by underscores (which Python's ``float`` and ``Decimal`` would read: ``1_08.5``
as 108.5), and a directory or a file of no known format is named as such (issue 27)."""
from __future__ import annotations

from pathlib import Path

import pytest

import cistrack.scenarios
from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations, reader_for, write_observations

EPOCH = "2026-03-01T00:00:00Z"
BOM = b"\xef\xbb\xbf"
FORMATS = [("ades-psv", ".psv"), ("ades-xml", ".xml"), ("mpc80", ".obs"), ("tdm", ".tdm"), ("csv", ".csv")]


@pytest.fixture(scope="module")
def radec():
    return read_observations(Path(cistrack.scenarios.__file__).parent / "real_data" / "observations.psv", EPOCH)


@pytest.fixture(scope="module")
def azel(tmp_path_factory):
    p = tmp_path_factory.mktemp("azel") / "obs.csv"
    p.write_text("time_utc,azimuth_deg,elevation_deg,range_km\n"
                 "2026-03-01T01:00:00Z,101.25,12.5,384000.5\n2026-03-01T01:40:00Z,102.5,14.0,384100.0\n")
    return read_observations(p, EPOCH)


@pytest.mark.parametrize("fmt, suffix", FORMATS)
def test_a_leading_byte_order_mark_is_accepted(tmp_path, fmt, suffix, radec, azel):
    src = azel if fmt == "csv" else radec
    p = tmp_path / f"obs{suffix}"
    write_observations(p, src, EPOCH, format=fmt)
    plain = read_observations(p, EPOCH)
    p.write_bytes(BOM + p.read_bytes())
    got = read_observations(p, EPOCH)
    assert len(got) == len(src) == len(plain)
    assert (got.times == plain.times).all() and (got.values == plain.values).all()


PSV = ("# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
       "X|CCD|705|2026-03-01T01:00:00.000000Z|{ra}|-7.5|1.0|1.0|Gaia3\n")
XML = ('<?xml version="1.0" encoding="UTF-8"?>\n<ades version="2022">\n<obsBlock>\n<obsData>\n<optical>\n'
       "<trkSub>X</trkSub>\n<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>{ra}</ra>\n"
       "<dec>5.5</dec>\n</optical>\n</obsData>\n</obsBlock>\n</ades>\n")
MPC = "     X        C2026 03 01.9_409709 21 56.561+08 01 17.71                     809\n"
TDM = ("CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00Z\nORIGINATOR = T\nMETA_START\n"
       "TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = X\nMODE = SEQUENTIAL\nPATH = 2,1\n"
       "ANGLE_TYPE = RADEC\nREFERENCE_FRAME = EME2000\nMETA_STOP\nDATA_START\n"
       "ANGLE_1 = 2026-03-01T01:00:00Z {ra}\nANGLE_2 = 2026-03-01T01:00:00Z 5.5\nDATA_STOP\n")
CSV = "time_utc,azimuth_deg,elevation_deg\n2026-03-01T01:00:00Z,{ra},12.3\n"
UNDERSCORED = [("ades-psv", ".psv", PSV.format(ra="1_02.5"), "ra"),
               ("ades-xml", ".xml", XML.format(ra="1_02.5"), "ra"),
               ("mpc80", ".obs", MPC, "day"),
               ("tdm", ".tdm", TDM.format(ra="1_02.5"), "ANGLE_1"),
               ("csv", ".csv", CSV.format(ra="1_01.2"), "azimuth_deg")]


@pytest.mark.parametrize("fmt, suffix, text, field", UNDERSCORED, ids=[u[0] for u in UNDERSCORED])
def test_numbers_with_underscores_are_refused(tmp_path, fmt, suffix, text, field):
    p = tmp_path / f"obs{suffix}"
    p.write_text(text)
    with pytest.raises(MeasurementError, match=field):
        read_observations(p, EPOCH)


def test_the_same_files_without_underscores_are_read(tmp_path):
    for fmt, suffix, text, _ in UNDERSCORED:
        p = tmp_path / f"ok{suffix}"
        p.write_text(text.replace("1_02.5", "102.5").replace("1_01.2", "101.2").replace("01.9_4097", "01.940972"))
        assert len(read_observations(p, EPOCH)) == 1, fmt


def test_a_directory_is_named_as_a_directory(tmp_path):
    d = tmp_path / "obs.csv"
    d.mkdir()
    with pytest.raises(MeasurementError, match="is a directory, not an observation file"):
        reader_for(d)
    with pytest.raises(MeasurementError, match="is a directory"):
        reader_for(tmp_path, format="csv")


def test_a_file_of_no_known_format_says_so(tmp_path):
    p = tmp_path / "passwd"
    p.write_text("root:x:0:0:root:/root:/bin/bash\n")
    with pytest.raises(MeasurementError, match="not an observation file of any known format"):
        reader_for(p)


WIDE = [("ades-psv", ".psv", PSV.format(ra="\uff1102.5"), "ra"),
        ("ades-xml", ".xml", XML.format(ra="\uff1102.5"), "ra"),
        ("tdm", ".tdm", TDM.format(ra="\uff1102.5"), "ANGLE_1"),
        ("csv", ".csv", CSV.format(ra="\uff1101.2"), "azimuth_deg")]


@pytest.mark.parametrize("fmt, suffix, text, field", WIDE, ids=[u[0] for u in WIDE])
def test_numbers_with_digits_of_another_script_are_refused(tmp_path, fmt, suffix, text, field):
    """A full-width digit (U+FF11) reads as 1 to Python's float and Decimal; no format allows it."""
    p = tmp_path / f"obs{suffix}"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(MeasurementError, match=field):
        read_observations(p, EPOCH)
