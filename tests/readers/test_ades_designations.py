"""ADES names an object by permID, provID, artSat (an artificial satellite) or trkSub. A row that gives both a permID and a provID
links them: rows named only by that provID are the same object, not a second one."""
from __future__ import annotations

import pytest

from cistrack.runs.observation_files import SeveralObjectsError, read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "# version=2022\npermID|provID|trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"


def _file(tmp_path, *ids: tuple[str, str, str]):
    body = "".join(f"{perm}|{prov}|{trk}|CCD|711|2026-03-01T{2 + k:02d}:00:00Z|10|5|0.5|0.5|Gaia3\n"
                   for k, (perm, prov, trk) in enumerate(ids))
    path = tmp_path / "ids.psv"
    path.write_text(HEAD + body)
    return path


def test_rows_named_by_a_provid_that_another_row_links_to_a_permid_are_one_object(tmp_path):
    ms = read_observations(_file(tmp_path, ("12345", "2026 AB", ""), ("", "2026 AB", ""), ("12345", "", "")), EPOCH)
    assert len(ms) == 3 and ms.meta["object"] == "12345"


def test_the_provid_chooses_the_same_object_as_its_permid(tmp_path):
    ms = read_observations(_file(tmp_path, ("12345", "2026 AB", ""), ("", "2026 AB", "")), EPOCH,
                           designation="2026 AB")
    assert len(ms) == 2


def test_a_trksub_is_not_linked_an_observer_may_reuse_it(tmp_path):
    with pytest.raises(SeveralObjectsError):
        read_observations(_file(tmp_path, ("", "2026 AB", "K1"), ("", "", "K1")), EPOCH)


def test_an_artificial_satellite_is_named_by_its_artsat(tmp_path):
    path = tmp_path / "artsat.psv"
    path.write_text("# version=2022\nartSat|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
                    + "".join(f"2025-010D|CCD|711|2026-03-01T{2 + k:02d}:00:00Z|10|5|0.5|0.5|Gaia3\n" for k in range(3)))
    ms = read_observations(path, EPOCH)
    assert len(ms) == 3 and ms.meta["object"] == "2025-010D"


def test_an_artsat_in_ades_xml_names_the_object_too(tmp_path):
    obs = "".join(f"<optical><artSat>2025-010D</artSat><mode>CCD</mode><stn>711</stn>"
                  f"<obsTime>2026-03-01T0{2 + k}:00:00Z</obsTime><ra>10</ra><dec>5</dec><rmsRA>0.5</rmsRA>"
                  f"<rmsDec>0.5</rmsDec><astCat>Gaia3</astCat></optical>" for k in range(3))
    path = tmp_path / "artsat.xml"
    path.write_text(f'<?xml version="1.0"?>\n<ades version="2022"><obsBlock><obsData>{obs}</obsData></obsBlock></ades>\n')
    assert read_observations(path, EPOCH).meta["object"] == "2025-010D"
