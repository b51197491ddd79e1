"""The full MPC observatory-code list ships with cistrack (issue 32, item 2): codes resolve to
WGS84 sites converted exactly from their parallax constants, a reader's ``sites`` also takes
parallax constants, and roving or space-based observers are refused with a message saying so."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.astro.sites import EARTH_EQUATORIAL_RADIUS_KM, observatory, observatory_codes
from cistrack.errors import MeasurementError, ParameterError
from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.plugins.readers.mpc80 import Mpc80Reader

EPOCH = "2026-03-01T00:00:00Z"
# Parallax constants as the MPC list gives them: East longitude (deg), rho cos phi', rho sin phi'
J04 = (343.48818, 0.881471, 0.471466)
G96 = (249.21128, 0.845107, 0.533611)


def _astropy_geodetic(lon_deg: float, rho_cos: float, rho_sin: float) -> tuple[float, float, float]:
    """Latitude (deg), East longitude (deg) and height (m) of parallax constants by astropy."""
    units = pytest.importorskip("astropy.units")
    coordinates = pytest.importorskip("astropy.coordinates")
    r = EARTH_EQUATORIAL_RADIUS_KM * 1000.0
    lon = math.radians(lon_deg)
    loc = coordinates.EarthLocation.from_geocentric(rho_cos * r * math.cos(lon), rho_cos * r * math.sin(lon),
                                                    rho_sin * r, unit=units.m)
    g = loc.to_geodetic("WGS84")
    return float(g.lat.deg), float(g.lon.deg), float(g.height.to(units.m).value)


@pytest.mark.parametrize("code, constants", [("J04", J04), ("G96", G96)])
def test_j04_and_g96_resolve_to_the_sites_astropy_computes_from_their_constants(code, constants):
    s = observatory(code)
    lat, lon, h = _astropy_geodetic(*constants)
    assert s.code == code
    assert s.latitude_deg == pytest.approx(lat, abs=1e-10)
    assert s.longitude_deg == pytest.approx(lon, abs=1e-10)
    assert s.height_m == pytest.approx(h, abs=1e-6)


def test_j04_is_the_optical_ground_station_on_tenerife_and_g96_mount_lemmon():
    j04, g96 = observatory("J04"), observatory("G96")
    assert "Tenerife" in j04.name and 28.2 < j04.latitude_deg < 28.4 and 2300 < j04.height_m < 2500
    assert "Lemmon" in g96.name and 32.3 < g96.latitude_deg < 32.5 and 2700 < g96.height_m < 2850


def test_the_bundled_list_is_the_full_mpc_list():
    codes = observatory_codes()
    assert len(codes) > 2500
    for code in ("000", "568", "675", "691", "703", "F51", "G96", "I41", "J04", "T05", "W68", "X05"):
        assert code in codes


@pytest.mark.parametrize("code, name", [("247", "Roving Observer"), ("270", "Roving Observer"),
                                        ("C51", "WISE"), ("250", "Hubble Space Telescope")])
def test_roving_and_space_based_codes_are_refused_saying_why(code, name):
    with pytest.raises(MeasurementError) as err:
        observatory(code)
    msg = str(err.value)
    assert repr(code) in msg and name in msg and "roving or space-based" in msg and "'sites'" in msg


def test_an_mpc80_file_from_a_roving_observer_is_refused_naming_the_line_and_columns(tmp_path):
    p = tmp_path / "roving.obs"
    p.write_text(f"{'':5}{'cis0001':<7}  C2026 03 01.500000" f"10 00 00.000+20 00 00.00{'':21}247\n")
    with pytest.raises(MeasurementError, match=r"line 1.*observatory code \(columns 78-80\).*roving or space-based"):
        Mpc80Reader().read(p, EPOCH)


def _psv(path, stn: str) -> None:
    path.write_text("# version=2017\n"
                    "permID |trkSub |mode|stn |obsTime                 |ra         |dec        |rmsRA|rmsDec|astCat\n"
                    f"       |cis0001|CCD |{stn}|2026-03-01T04:20:00.000Z|101.5      |-12.5      |0.5  |0.5   |Gaia3\n")


def test_a_site_given_by_parallax_constants_is_the_site_of_those_constants(tmp_path):
    p = tmp_path / "obs.psv"
    _psv(p, "TST")
    lon, rc, rs = J04
    reader = AdesPsvReader(sites={"TST": {"longitude_deg": lon, "rho_cos_phi": rc, "rho_sin_phi": rs, "name": "test"}})
    site = reader.read(p, EPOCH).site_table["TST"]
    lat, lon_g, h = _astropy_geodetic(*J04)
    assert (site.latitude_deg, site.longitude_deg) == (pytest.approx(lat, abs=1e-10), pytest.approx(lon_g, abs=1e-10))
    assert site.height_m == pytest.approx(h, abs=1e-6) and site.name == "test"


def test_a_site_given_by_parallax_constants_matches_the_geodetic_one_the_reader_builds(tmp_path):
    p = tmp_path / "obs.psv"
    _psv(p, "TST")
    j04 = observatory("J04")
    geodetic = AdesPsvReader(sites={"TST": [j04.latitude_deg, j04.longitude_deg, j04.height_m]}).read(p, EPOCH)
    parallax = AdesPsvReader(sites={"TST": dict(zip(("longitude_deg", "rho_cos_phi", "rho_sin_phi"), J04))}).read(p, EPOCH)
    a, b = geodetic.site_table["TST"].ecef_km(), parallax.site_table["TST"].ecef_km()
    assert np.allclose(a, b, atol=1e-9, rtol=0)            # the same point to a micrometre
    assert math.hypot(b[0], b[1]) / EARTH_EQUATORIAL_RADIUS_KM == pytest.approx(J04[1], abs=1e-12)
    assert b[2] / EARTH_EQUATORIAL_RADIUS_KM == pytest.approx(J04[2], abs=1e-12)


@pytest.mark.parametrize("spec, words", [
    ({"longitude_deg": 10.0, "rho_cos_phi": 0.8}, "needs either latitude_deg, longitude_deg, height_m"),
    ({"longitude_deg": 10.0, "rho_cos_phi": 0.8, "rho_sin_phi": 0.6, "height_m": 3.0}, "rho_sin_phi"),
    ({"longitude_deg": 10.0, "rho_cos_phi": -0.8, "rho_sin_phi": 0.6}, "rho_cos_phi -0.8 must be >= 0"),
    ({"longitude_deg": 10.0, "rho_cos_phi": 0.8, "rho_sin_phi": math.nan}, "finite numbers"),
    ({"longitude_deg": 10.0, "rho_cos_phi": 0.0, "rho_sin_phi": 0.0}, "geocentre"),
    ({"longitude_deg": 10.0, "rho_cos_phi": 0.5, "rho_sin_phi": 0.5}, "height_m")])
def test_bad_parallax_constants_are_refused_naming_the_parameter_site_and_what_is_allowed(spec, words):
    with pytest.raises(ParameterError) as err:
        AdesPsvReader(sites={"TST": spec})
    msg = str(err.value)
    assert "sites" in msg and "TST" in msg
    assert words in msg, msg
