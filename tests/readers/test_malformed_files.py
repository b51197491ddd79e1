"""Each reader refuses malformed files with a message naming the line and the field, and quotes
no more of the file than the offending field (the object name SECRETX on the same line never
appears in the message)."""
from __future__ import annotations

import pytest

from cistrack.errors import MeasurementError
from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.plugins.readers.ades_xml import AdesXmlReader
from cistrack.plugins.readers.csv_file import CsvReader
from cistrack.plugins.readers.mpc80 import Mpc80Reader
from cistrack.plugins.readers.tdm import TdmReader

EPOCH = "2026-03-01T00:00:00Z"

# -- ADES PSV -------------------------------------------------------------------------------------
PSV_HEAD = "# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
PSV_OK = "SECRETX|CCD|705|2026-03-01T01:00:00.000000Z|102.5|-7.5|1.0|1.0|Gaia3\n"


def psv(row: str, head: str = PSV_HEAD) -> str:
    return head + PSV_OK + row + "\n"


PSV_CASES = [
    ("ra not a number", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|abc|-7.5|1.0|1.0|Gaia3"), 4, "ra"),
    ("ra 360", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|360.0|-7.5|1.0|1.0|Gaia3"), 4, "ra"),
    ("dec beyond the pole", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|91|1.0|1.0|Gaia3"), 4, "dec"),
    ("dec empty", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10||1.0|1.0|Gaia3"), 4, "dec"),
    ("time not ISO", psv("SECRETX|CCD|705|01/03/2026 02:00|10|5|1.0|1.0|Gaia3"), 4, "obsTime"),
    ("time not UTC", psv("SECRETX|CCD|705|2026-03-01T02:00:00+02:00|10|5|1.0|1.0|Gaia3"), 4, "obsTime"),
    ("negative rmsDec", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|5|1.0|-1.0|Gaia3"), 4, "rmsDec"),
    ("rmsRA nan", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|5|nan|1.0|Gaia3"), 4, "rmsRA"),
    ("rmsRA beyond the sky", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|5|1e300|1.0|Gaia3"), 4, "rmsRA"),
    ("rmsDec below a micro-arcsecond", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|5|1.0|1e-30|Gaia3"), 4, "rmsDec"),
    ("unknown station", psv("SECRETX|CCD|Q9Z|2026-03-01T02:00:00Z|10|5|1.0|1.0|Gaia3"), 4, "stn"),
    ("too few fields", psv("SECRETX|CCD|705|2026-03-01T02:00:00Z|10|5|1.0"), 4, "(field count)"),
    ("no object", psv("|CCD|705|2026-03-01T02:00:00Z|10|5|1.0|1.0|Gaia3"), 4, "permID/provID/artSat/trkSub"),
    ("repeated time and site", psv("SECRETX|CCD|705|2026-03-01T01:00:00.000000Z|10|5|1.0|1.0|Gaia3"), 4, "obsTime"),
    ("header lacks dec", "# version=2022\ntrkSub|stn|obsTime|ra\n", 2, "dec"),
    ("unknown version", "# version=banana\ntrkSub|mode|stn|obsTime|ra|dec\n", 1, "version"),
    ("header repeats a field", "# version=2022\nstn|obsTime|ra|dec|ra\n", 2, "ra"),
    ("longitude beyond a turn", "# version=2022\ntrkSub|stn|obsTime|ra|dec|sys|ctr|pos1|pos2|pos3\n"
     "SECRETX|XX1|2026-03-01T02:00:00Z|10|5|WGS84|399|1000|30|2075\n", 3, "pos1: '1000'"),
    ("non-WGS84 position", "# version=2022\ntrkSub|stn|obsTime|ra|dec|sys|ctr|pos1|pos2|pos3\n"
     "SECRETX|247|2026-03-01T02:00:00Z|10|5|ICRF|399|1|2|3\n", 3, "sys"),
]

# -- ADES XML -------------------------------------------------------------------------------------


def xml(fields: str, extra: str = "") -> str:
    return ('<?xml version="1.0" encoding="UTF-8"?>\n<ades version="2022">\n<obsBlock>\n<obsData>\n'
            "<optical>\n<trkSub>SECRETX</trkSub>\n" + fields + "</optical>\n" + extra + "</obsData>\n</obsBlock>\n</ades>\n")


GOOD_FIELDS = ("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>10.5</ra>\n<dec>5.5</dec>\n")

XML_CASES = [
    ("ra not a number", xml("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>ten</ra>\n<dec>5</dec>\n"), 9, "ra"),
    ("dec missing", xml("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>10</ra>\n"), 5, "dec"),
    ("dec beyond the pole", xml("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>10</ra>\n<dec>-95</dec>\n"), 10, "dec"),
    ("time not a time", xml("<stn>705</stn>\n<obsTime>yesterday</obsTime>\n<ra>10</ra>\n<dec>5</dec>\n"), 8, "obsTime"),
    ("unknown station", xml("<stn>ZZ9</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra>10</ra>\n<dec>5</dec>\n"), 7, "stn"),
    ("negative rmsRA", xml(GOOD_FIELDS + "<rmsRA>-0.5</rmsRA>\n"), 11, "rmsRA"),
    ("field twice", xml(GOOD_FIELDS + "<ra>11</ra>\n"), 11, "ra"),
    ("element inside a field", xml("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obsTime>\n<ra><b>1</b></ra>\n<dec>5</dec>\n"), 9, "ra"),
    ("not well-formed", xml("<stn>705</stn>\n<obsTime>2026-03-01T01:00:00Z</obs>\n<ra>10</ra>\n<dec>5</dec>\n"), 8, "(XML)"),
    ("wrong root", '<?xml version="1.0"?>\n<observations>\n</observations>\n', 2, "<ades>"),
    ("entity declaration", '<?xml version="1.0"?>\n<!DOCTYPE ades [<!ENTITY x "y">]>\n<ades></ades>\n', 2, "(DOCTYPE)"),
    ("nested optical", xml(GOOD_FIELDS + "<optical>\n"), 11, "<optical>"),
    ("another vocabulary's ades", xml(GOOD_FIELDS).replace('<ades version="2022">', '<ades version="2022" xmlns="http://example.com/foo">'), 2, "<ades>"),
]

# -- MPC 80 ---------------------------------------------------------------------------------------
MPC_OK = "     SECRETX  C2026 03 01.04167606 51 33.239-07 54 18.29                     705"


def mpc(line: str) -> str:
    assert len(line) == 80 or "length" in line or True
    return MPC_OK + "\n" + line + "\n"


def col(s: str, start: int, text: str) -> str:
    """``s`` with ``text`` put at 1-based column ``start``."""
    return s[:start - 1] + text + s[start - 1 + len(text):]


MPC_CASES = [
    ("short line", mpc(MPC_OK[:70]), 2, "(line length)"),
    ("satellite observation", mpc(col(MPC_OK, 15, "S")), 2, "note 2 (column 15)"),
    ("unknown type", mpc(col(MPC_OK, 15, "#")), 2, "note 2 (column 15)"),
    ("month not digits", mpc(col(MPC_OK, 21, "0x")), 2, "date month"),
    ("day 30 february", mpc(col(col(MPC_OK, 21, "02"), 24, "30")), 2, "date (columns 16-32)"),
    ("day not a number", mpc(col(MPC_OK, 24, "ab.cdefgh")), 2, "date day"),
    ("RA hours 24", mpc(col(MPC_OK, 33, "24")), 2, "RA (columns 33-44)"),
    ("RA seconds letters", mpc(col(MPC_OK, 39, "3x.239")), 2, "RA seconds"),
    ("Dec without sign", mpc(col(MPC_OK, 45, " ")), 2, "Dec (columns 45-56)"),
    ("Dec minutes 61", mpc(col(MPC_OK, 49, "61")), 2, "Dec (columns 45-56)"),
    ("unknown observatory", mpc(col(MPC_OK, 78, "ZZ9")), 2, "observatory code"),
    ("blank observatory", mpc(col(MPC_OK, 78, "   ")), 2, "observatory code"),
    ("repeated time and site", mpc(col(MPC_OK, 55, "3")), 2, "date (columns 16-32)"),
]

# -- TDM ------------------------------------------------------------------------------------------
TDM_HEAD = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"


def tdm(meta: str = "TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n",
        data: str = "ANGLE_1 = 2026-03-01T01:00:00 10.5\nANGLE_2 = 2026-03-01T01:00:00 20.5\n",
        head: str = TDM_HEAD, tail: str = "DATA_STOP\n") -> str:
    return head + "META_START\n" + meta + "META_STOP\nDATA_START\n" + data + tail


TDM_CASES = [
    ("no version", tdm(head="ORIGINATOR = SECRETX\n"), 2, "CCSDS_TDM_VERS"),
    ("unknown header keyword", tdm(head=TDM_HEAD + "FOO = SECRETX\n"), 4, "FOO"),
    ("time system TAI", tdm(meta="TIME_SYSTEM = TAI\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"), 5, "TIME_SYSTEM"),
    ("angle type XEYN", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = XEYN\n"), 8, "ANGLE_TYPE"),
    ("RADEC without frame", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = RADEC\n"), 9, "REFERENCE_FRAME"),
    ("unknown station", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = NOWHERE\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"), 6, "PARTICIPANT_1"),
    ("missing participant", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"), 8, "PARTICIPANT_1"),
    ("bad epoch", tdm(data="ANGLE_1 = 2026/03/01 10.5\nANGLE_2 = 2026-03-01T01:00:00 20.5\n"), 11, "ANGLE_1 epoch"),
    ("value not a number", tdm(data="ANGLE_1 = 2026-03-01T01:00:00 1O.5\nANGLE_2 = 2026-03-01T01:00:00 20.5\n"), 11, "ANGLE_1 value"),
    ("elevation 95", tdm(data="ANGLE_1 = 2026-03-01T01:00:00 10.5\nANGLE_2 = 2026-03-01T01:00:00 95\n"), 12, "ANGLE_2 value"),
    ("unpaired angle", tdm(data="ANGLE_1 = 2026-03-01T01:00:00 10.5\nANGLE_2 = 2026-03-01T01:05:00 20.5\n"), 11, "ANGLE_2"),
    ("range data", tdm(data="RANGE = 2026-03-01T01:00:00 1000\n"), 11, "RANGE"),
    ("stop before start", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"
                               "START_TIME = 2026-03-02T00:00:00\nSTOP_TIME = 2026-03-01T00:00:00\n"), 10, "STOP_TIME"),
    ("data outside start to stop", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\n"
                                        "ANGLE_TYPE = AZEL\nSTART_TIME = 2026-03-01T02:00:00\n"
                                        "STOP_TIME = 2026-03-01T03:00:00\n"), 13, "ANGLE_1 epoch"),
    ("unknown cistrack comment", tdm(meta="COMMENT cistrack sigma_arcsec ANGLE_1=1.0 junk\nTIME_SYSTEM = UTC\n"
                                          "PARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"), 5,
     "COMMENT cistrack"),
    ("sigma comment beyond the sky", tdm(meta="COMMENT cistrack sigma_arcsec ANGLE_1=1e300 ANGLE_2=1\nTIME_SYSTEM = UTC\n"
                                              "PARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nANGLE_TYPE = AZEL\n"), 5,
     "COMMENT cistrack sigma_arcsec"),
    ("missing DATA_STOP", tdm(tail=""), 12, "DATA_STOP"),
    ("not key = value", tdm(meta="TIME_SYSTEM UTC SECRETX\n"), 5, "(keyword)"),
    ("day of year 366 in 2026", tdm(data="ANGLE_1 = 2026-366T01:00:00 10.5\nANGLE_2 = 2026-366T01:00:00 20.5\n"), 11, "ANGLE_1 epoch"),
    ("mode not sequential", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\nMODE = INTEGRATED\n"
                                     "ANGLE_TYPE = AZEL\n"), 8, "MODE"),
    ("path through participants never named", tdm(meta="TIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = SECRETX\n"
                                                        "PATH = 7,9\nANGLE_TYPE = AZEL\n"), 8, "PATH"),
]

# -- CSV ------------------------------------------------------------------------------------------
CSV_HEAD = "time_utc,azimuth_deg,elevation_deg,site\n"
CSV_OK = "2026-03-01T01:00:00Z,10.5,20.5,705\n"


def csv(row: str) -> str:
    return CSV_HEAD + CSV_OK + row + "\n"


CSV_CASES = [
    ("azimuth not a number", csv("2026-03-01T02:00:00Z,abc,20,705"), 3, "azimuth_deg"),
    ("azimuth 360", csv("2026-03-01T02:00:00Z,360,20,705"), 3, "azimuth_deg"),
    ("elevation 91", csv("2026-03-01T02:00:00Z,10,91,705"), 3, "elevation_deg"),
    ("elevation inf", csv("2026-03-01T02:00:00Z,10,inf,705"), 3, "elevation_deg"),
    ("time not ISO", csv("tomorrow,10,20,705"), 3, "time_utc"),
    ("time not later", csv("2026-03-01T00:30:00Z,10,20,705"), 3, "time_utc"),
    ("unknown site", csv("2026-03-01T02:00:00Z,10,20,ZZ9"), 3, "site"),
    ("too many fields", csv("2026-03-01T02:00:00Z,10,20,705,1"), 3, "fields (columns)"),
    ("empty azimuth", csv("2026-03-01T02:00:00Z,,20,705"), 3, "azimuth_deg"),
    ("sigma below a micro-arcsecond", "time_utc,azimuth_deg,elevation_deg,site,sigma_azimuth_arcsec\n"
     "2026-03-01T01:00:00Z,10.5,20.5,705,1e-30\n", 2, "sigma_azimuth_arcsec"),
    ("unknown column", "time_utc,azimuth_deg,elevation_deg,colour\n", 1, "colour"),
]

ALL = ([("ades-psv", AdesPsvReader, ".psv") + c for c in PSV_CASES]
       + [("ades-xml", AdesXmlReader, ".xml") + c for c in XML_CASES]
       + [("mpc80", Mpc80Reader, ".obs") + c for c in MPC_CASES]
       + [("tdm", TdmReader, ".tdm") + c for c in TDM_CASES]
       + [("csv", CsvReader, ".csv") + c for c in CSV_CASES])


@pytest.mark.parametrize("fmt", ["ades-psv", "ades-xml", "mpc80", "tdm", "csv"])
def test_each_format_has_at_least_ten_malformed_cases(fmt):
    assert sum(1 for c in ALL if c[0] == fmt) >= 10


@pytest.mark.parametrize("fmt, reader, suffix, case, text, line, field", ALL,
                         ids=[f"{c[0]}: {c[3]}" for c in ALL])
def test_malformed_file_is_refused_naming_line_and_field(tmp_path, fmt, reader, suffix, case, text, line, field):
    p = tmp_path / ("bad" + suffix)
    p.write_text(text)
    with pytest.raises(MeasurementError) as info:
        reader().read(p, EPOCH)
    msg = str(info.value)
    assert str(p) in msg
    assert f"line {line}" in msg, msg
    assert field in msg, msg
    assert "SECRETX" not in msg, msg


@pytest.mark.parametrize("ra", ["360.0", "-31.2"])
def test_an_ades_ra_outside_its_range_is_refused_quoting_the_half_open_interval(tmp_path, ra):
    """360 had been refused as 'must be below 360 degrees', other RAs as outside [0.0, 360.0], a
    closed interval holding 360 (probe I8)."""
    p = tmp_path / "ra.psv"
    p.write_text(psv(f"SECRETX|CCD|705|2026-03-01T02:00:00Z|{ra}|-7.5|1.0|1.0|Gaia3"))
    with pytest.raises(MeasurementError, match=rf"'{ra}' is outside \[0, 360\) degrees"):
        AdesPsvReader().read(p, EPOCH)


def test_an_ades_xml_file_of_radar_records_only_says_optical_astrometry_is_read(tmp_path):
    p = tmp_path / "radar.xml"
    p.write_text(xml(GOOD_FIELDS).replace("<optical>", "<radar>").replace("</optical>", "</radar>"))
    with pytest.raises(MeasurementError, match=r"1 <radar> records and no optical one"):
        AdesXmlReader().read(p, EPOCH)


def test_radar_records_beside_optical_ones_are_said_to_be_left_out(tmp_path, caplog):
    p = tmp_path / "mixed.xml"
    radar = "<radar>\n<trkSub>SECRETX</trkSub>\n<stn>705</stn>\n</radar>\n"
    p.write_text(xml(GOOD_FIELDS, extra=radar))
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        assert len(AdesXmlReader().read(p, EPOCH)) == 1
    assert "1 <radar> records are not read" in caplog.text


@pytest.mark.parametrize("tail", ["\x1a\n", "\x1a"])
def test_an_mpc_file_ending_in_a_dos_end_of_file_byte_reads_as_without_it(tmp_path, tail):
    """Probe I8: the byte on its own line had been refused as "line 2, field (line length): 1 characters"."""
    clean, dos = tmp_path / "clean.obs", tmp_path / "dos.obs"
    clean.write_text(MPC_OK + "\n")
    dos.write_text(MPC_OK + ("\n" if tail.endswith("\n") else "") + tail)
    a = Mpc80Reader().read(clean, "2026-03-01T00:00:00Z")
    b = Mpc80Reader().read(dos, "2026-03-01T00:00:00Z")
    assert len(b) == len(a) == 1 and (b.values == a.values).all()
