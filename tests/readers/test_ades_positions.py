"""Observatory positions given in an ADES file (sys, ctr, pos1, pos2, pos3): only Earth-fixed
WGS84 positions are read, and a position given under a bundled MPC code far from the code's own
place is said to replace it."""
from __future__ import annotations

import pytest

from cistrack.astro.sites import observatory
from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "# version=2022\ntrkSub|stn|obsTime|ra|dec|sys|ctr|pos1|pos2|pos3\n"


def _psv(tmp_path, ctr: str = "399", place: tuple = (10.0, 20.0, 30.0), stn: str = "XY1"):
    rows = "".join(f"X|{stn}|2026-03-01T0{h}:00:00Z|10|5|WGS84|{ctr}|{place[0]!r}|{place[1]!r}|{place[2]!r}\n"
                   for h in (2, 3))
    path = tmp_path / "pos.psv"
    path.write_text(HEAD + rows)
    return path


def _xml(tmp_path, ctr: str):
    fields = f"<trkSub>X</trkSub><stn>XY1</stn><obsTime>2026-03-01T02:00:00Z</obsTime><ra>10</ra><dec>5</dec>" \
             f"<sys>WGS84</sys>\n<ctr>{ctr}</ctr><pos1>10</pos1><pos2>20</pos2><pos3>30</pos3>"
    path = tmp_path / "pos.xml"
    path.write_text(f'<ades version="2022"><obsBlock><obsData>\n<optical>{fields}</optical>\n'
                    "</obsData></obsBlock></ades>\n")
    return path


@pytest.mark.parametrize("ctr", ["301", "banana", "10"])
def test_a_position_about_another_centre_than_the_earth_is_refused_naming_file_line_and_value(tmp_path, ctr):
    with pytest.raises(MeasurementError, match=rf"pos\.psv, line 3, field ctr: '{ctr}': a WGS84 position is on the "
                                               r"Earth: ctr = 399 \(or no ctr\)"):
        read_observations(_psv(tmp_path, ctr), EPOCH)


def test_the_xml_reader_refuses_it_the_same_way(tmp_path):
    with pytest.raises(MeasurementError, match=r"pos\.xml, line 3, field ctr: '301'"):
        read_observations(_xml(tmp_path, "301"), EPOCH)


@pytest.mark.parametrize("ctr", ["399", ""])
def test_an_earth_centred_position_or_one_without_ctr_is_read(tmp_path, ctr):
    ms = read_observations(_psv(tmp_path, ctr), EPOCH)
    assert ms.site_table["XY1"].latitude_deg == 20.0 and ms.site_table["XY1"].longitude_deg == 10.0


def test_a_position_given_under_an_mpc_code_far_from_it_is_said_once_naming_both_places(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_psv(tmp_path, stn="711"), EPOCH)
    assert ms.site_table[ms.sites[0]].latitude_deg == 20.0  # the file's position is used
    said = [r.getMessage() for r in caplog.records if "replaces the MPC observatory 711" in r.getMessage()]
    assert len(said) == 1
    assert said[0].startswith(f"{tmp_path / 'pos.psv'}, line 3: station '711' is given at latitude 20, longitude 10, "
                              "height 30 m")
    assert "(McDonald Observatory, Fort Davis: 30.6715, -104.0215, 2103 m; 9,699.0 km away)" in said[0]


def test_a_position_given_within_a_kilometre_of_its_mpc_code_says_nothing(tmp_path, caplog):
    mcdonald = observatory("711")
    near = (mcdonald.longitude_deg + 360.0, mcdonald.latitude_deg + 0.005, mcdonald.height_m + 300.0)
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(_psv(tmp_path, stn="711", place=near), EPOCH)
    assert "replaces" not in caplog.text
