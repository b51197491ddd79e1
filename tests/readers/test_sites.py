"""Observing sites: MPC codes from the bundled table, geodetic coordinates, per-measurement sites."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.errors import MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.sites import EARTH_EQUATORIAL_RADIUS_KM, Site, observatory, observatory_codes


@pytest.mark.parametrize("code", ["568", "705", "711", "807", "F51", "000"])
def test_observatory_code_gives_a_site_whose_parallax_constants_match_the_table(code):
    import cistrack.astro.sites as sites
    lon, rc, rs, _name = sites._table()[code]
    s = observatory(code)
    x, y, z = s.ecef_km()
    assert math.hypot(x, y) / EARTH_EQUATORIAL_RADIUS_KM == pytest.approx(rc, abs=1e-12)
    assert z / EARTH_EQUATORIAL_RADIUS_KM == pytest.approx(rs, abs=1e-12)
    assert math.degrees(math.atan2(y, x)) % 360.0 == pytest.approx(lon % 360.0, abs=1e-9)


def test_geodetic_conversion_agrees_with_erfa():
    erfa = pytest.importorskip("erfa")
    for code in observatory_codes():
        if code == "500":
            continue
        s = observatory(code)
        lon, lat, h = erfa.gc2gd(1, np.array(s.ecef_km()) * 1000.0)
        assert s.latitude_deg == pytest.approx(math.degrees(lat), abs=1e-10)
        assert s.height_m == pytest.approx(h, abs=1e-6)


def test_maunakea_is_high_on_hawaii():
    s = observatory("568")
    assert s.latitude_deg == pytest.approx(19.826, abs=0.01)
    assert s.longitude_deg == pytest.approx(-155.472, abs=0.01)
    assert 4000 < s.height_m < 4300


def test_unknown_code_and_geocentre_are_refused_with_the_code():
    with pytest.raises(MeasurementError, match="'ZZZ'.*explicitly"):
        observatory("ZZZ")
    with pytest.raises(MeasurementError, match="geocentre"):
        observatory("500")


def test_a_lower_case_code_is_refused_with_the_code_it_would_be():
    """Probe N: 'g96' had been refused as not in the MPC list, with no hint of G96."""
    with pytest.raises(MeasurementError, match=r"'g96' is not in the MPC list .* \(did you mean 'G96', .*Mt. Lemmon"):
        observatory("g96")


def test_an_unknown_code_gets_no_hint():
    with pytest.raises(MeasurementError) as err:
        observatory("ZZ9")
    assert "did you mean" not in str(err.value)


def test_site_refuses_out_of_range_latitude():
    with pytest.raises(MeasurementError, match="latitude_deg"):
        Site(91.0, 0.0, 0.0, name="x")


def _two_site_set():
    table = {"705": observatory("705"), "711": observatory("711")}
    return MeasurementSet([0.1, 0.2, 0.3], np.ones((3, 2)), np.full((3, 2), 1e-5), ("right_ascension", "declination"),
                          sites=["705", "711", "705"], kinds=["radec"] * 3, site_table=table)


def test_each_measurement_carries_its_site_and_type():
    ms = _two_site_set()
    m = ms[1]
    assert (m.site, m.kind, m.names) == ("711", "radec", ("right_ascension", "declination"))
    assert ms.site_keys() == ["705", "711"]
    sub = ms.subset(np.array([False, True, True]))
    assert sub.sites.tolist() == ["711", "705"] and sub.site_table == ms.site_table


def test_a_mixed_set_names_each_measurement_by_its_type():
    ms = MeasurementSet([0.1, 0.2], np.ones((2, 2)), np.full((2, 2), 1e-5), ("angle_1", "angle_2"),
                        kinds=["azel", "radec"])
    assert ms[0].names == ("azimuth", "elevation") and ms[1].names == ("right_ascension", "declination")


def test_a_set_refuses_sites_missing_from_its_table_and_types_contradicting_names():
    with pytest.raises(MeasurementError, match="site table"):
        MeasurementSet([0.1], np.ones((1, 2)), np.ones((1, 2)), ("azimuth", "elevation"), sites=["X"])
    with pytest.raises(MeasurementError, match="mixed set"):
        MeasurementSet([0.1], np.ones((1, 2)), np.ones((1, 2)), ("azimuth", "elevation"), kinds=["radec"])


def test_a_set_without_sites_keeps_the_old_behaviour():
    ms = MeasurementSet([0.1], np.ones((1, 2)), np.ones((1, 2)), ("azimuth", "elevation"))
    assert ms[0].site == "" and ms[0].kind == "azel" and ms.site_keys() == [""]
