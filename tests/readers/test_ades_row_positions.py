"""An ADES position (sys, pos1, pos2, pos3) is its record's own: a record of code 711 at another
place is read at that place, the code's other records at McDonald Observatory, whatever the
order of the rows."""
from __future__ import annotations

import pytest

from cistrack.astro.sites import observatory
from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations, write_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "# version=2022\ntrkSub|stn|obsTime|ra|dec|sys|ctr|pos1|pos2|pos3\n"
PLAIN_711 = "X|711|2026-03-01T02:00:00Z|10|5|||||\n"
PLACED_711 = "X|711|2026-03-01T03:00:00Z|10|5|WGS84|399|10.0|20.0|30.0\n"


def _read(tmp_path, *rows: str):
    path = tmp_path / "rows.psv"
    path.write_text(HEAD + "".join(rows))
    return read_observations(path, EPOCH)


def _place(ms, i: int) -> tuple[float, float, float]:
    site = ms.site_table[ms.sites[i]]
    return site.latitude_deg, site.longitude_deg, site.height_m


def test_a_record_without_a_position_keeps_the_bundled_place_of_its_code(tmp_path):
    ms = _read(tmp_path, PLAIN_711, PLACED_711)
    mcdonald = observatory("711")
    assert _place(ms, 0) == (mcdonald.latitude_deg, mcdonald.longitude_deg, mcdonald.height_m)


def test_a_record_with_a_position_is_read_at_it(tmp_path):
    ms = _read(tmp_path, PLAIN_711, PLACED_711)
    assert _place(ms, 1) == (20.0, 10.0, 30.0)


def test_a_position_on_a_later_record_of_the_code_is_read_as_on_an_earlier_one(tmp_path):
    first = _read(tmp_path, PLACED_711, PLAIN_711)
    later = _read(tmp_path, PLAIN_711, PLACED_711)
    assert [_place(first, i) for i in (0, 1)] == [_place(later, i) for i in (0, 1)]


def test_the_warning_names_the_record_that_gives_the_position(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        _read(tmp_path, PLAIN_711, PLACED_711)
    assert f"{tmp_path / 'rows.psv'}, line 4: station '711' is given at latitude 20" in caplog.text


def test_a_position_at_the_codes_own_place_is_the_code(tmp_path):
    m = observatory("711")
    ms = _read(tmp_path, PLAIN_711, f"X|711|2026-03-01T03:00:00Z|10|5|WGS84|399|{m.longitude_deg!r}|"
                                    f"{m.latitude_deg!r}|{m.height_m!r}\n")
    assert ms.sites.tolist() == ["711", "711"]


def test_the_ades_writer_gives_each_record_its_place_back(tmp_path):
    ms = _read(tmp_path, PLAIN_711, PLACED_711)
    write_observations(tmp_path / "again.psv", ms, EPOCH)
    again = read_observations(tmp_path / "again.psv", EPOCH)
    assert [_place(again, i) for i in (0, 1)] == [_place(ms, i) for i in (0, 1)]


@pytest.mark.parametrize("order", ["placed first", "placed later"])
def test_a_record_without_a_position_under_a_code_outside_the_list_is_refused_in_any_order(tmp_path, order):
    placed, plain = PLACED_711.replace("711", "XY1"), PLAIN_711.replace("711", "XY1")
    rows = (placed, plain) if order == "placed first" else (plain, placed)
    line = 4 if order == "placed first" else 3
    with pytest.raises(MeasurementError, match=rf"rows\.psv, line {line}, field stn: MPC observatory code 'XY1' is not "
                                               r"in the MPC list .*or this row's position"):
        _read(tmp_path, *rows)
