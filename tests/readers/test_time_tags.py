"""Observation times the readers refuse by what they are: a leap second (second 60), which
cistrack's UTC times cannot hold, and an ADES obsTime without the Z that ADES requires; and
times on both sides of a leap second, which are elapsed time apart, not clock time."""
from __future__ import annotations

import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations
from cistrack.units import TU_S

EPOCH = "2026-03-01T00:00:00Z"


def _psv(tmp_path, first: str):
    path = tmp_path / "times.psv"
    path.write_text(f"# version=2022\ntrkSub|stn|obsTime|ra|dec\nX|711|{first}|10|5\nX|711|2026-03-02T03:00:00Z|10|5\n")
    return path


def _xml(tmp_path, first: str):
    one = "<optical><trkSub>X</trkSub><stn>711</stn><obsTime>{}</obsTime><ra>10</ra><dec>5</dec></optical>\n"
    path = tmp_path / "times.xml"
    path.write_text('<ades version="2022"><obsBlock><obsData>\n' + one.format(first)
                    + one.format("2026-03-02T03:00:00Z") + "</obsData></obsBlock></ades>\n")
    return path


# -- leap seconds -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("time", ["2016-12-31T23:59:60Z", "2016-12-31T23:59:60.25Z"])
def test_an_ades_leap_second_is_refused_as_a_leap_second_naming_the_field(tmp_path, time):
    with pytest.raises(MeasurementError, match=r"times\.psv, line 3, field obsTime: '2016-12-31T23:59:60.*': is a "
                                               r"leap second \(second 60\): leap-second time tags are not supported"):
        read_observations(_psv(tmp_path, time), EPOCH)


def test_the_xml_reader_says_the_same(tmp_path):
    with pytest.raises(MeasurementError, match=r"times\.xml, line 2, field obsTime: .*is a leap second"):
        read_observations(_xml(tmp_path, "2016-12-31T23:59:60Z"), EPOCH)


def test_a_csv_leap_second_is_refused_as_a_leap_second_naming_the_column(tmp_path):
    path = tmp_path / "times.csv"
    path.write_text("time_utc,azimuth_deg,elevation_deg,site\n2016-12-31T23:59:60Z,120.5,40.2,711\n"
                    "2017-01-01T00:45:00Z,120.7,40.5,711\n")
    with pytest.raises(MeasurementError, match=r"line 2: time_utc '2016-12-31T23:59:60Z' is a leap second \(second "
                                               r"60\): leap-second time tags are not supported"):
        read_observations(path, EPOCH)


def test_ades_rows_on_both_sides_of_a_leap_second_are_one_second_further_apart_than_their_labels(tmp_path):
    path = tmp_path / "leap.psv"
    path.write_text("# version=2022\ntrkSub|stn|obsTime|ra|dec\nX|809|2016-12-31T23:30:00Z|10|5\n"
                    "X|809|2017-01-01T00:05:00Z|10.1|5\n")
    times = read_observations(path, "2016-12-31T23:00:00Z").times * TU_S
    assert times[0] == pytest.approx(1800.0, abs=1e-6)
    assert times[1] - times[0] == pytest.approx(35 * 60 + 1.0, abs=1e-6)     # 35 min on the clock + the leap second


def test_csv_rows_on_both_sides_of_a_leap_second_are_one_second_further_apart_than_their_labels(tmp_path):
    path = tmp_path / "leap.csv"
    path.write_text("time_utc,azimuth_deg,elevation_deg,site\n2016-12-31T23:59:59Z,120.5,40.2,711\n"
                    "2017-01-01T00:00:00Z,120.7,40.5,711\n")
    times = read_observations(path, "2016-12-31T23:00:00Z").times * TU_S
    assert times[1] - times[0] == pytest.approx(2.0, abs=1e-6)


# -- the Z of an ADES obsTime -------------------------------------------------------------------------------

@pytest.mark.parametrize("time", ["2026-03-01T02:00:00", "2026-03-01T02:00:00.5", "2026-03-01T02:00:00+00:00",
                                  "2026-03-01T02:00:00+01:00"])
def test_an_ades_time_without_the_z_is_refused_as_one_that_is_not_utc(tmp_path, time):
    with pytest.raises(MeasurementError, match=r"times\.psv, line 3, field obsTime: .*must be UTC \(end in Z\)"):
        read_observations(_psv(tmp_path, time), EPOCH)


def test_the_xml_reader_refuses_it_the_same_way(tmp_path):
    with pytest.raises(MeasurementError, match=r"times\.xml, line 2, field obsTime: .*must be UTC \(end in Z\)"):
        read_observations(_xml(tmp_path, "2026-03-01T02:00:00"), EPOCH)


def test_a_time_ending_in_z_is_read(tmp_path):
    assert len(read_observations(_psv(tmp_path, "2026-03-01T02:00:00.123Z"), EPOCH)) == 2
