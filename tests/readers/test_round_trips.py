"""Each writer's output reads back as what was written: exact angles and sigmas (MPC 80: the
format's resolution), times to 1 microsecond, every site and type; writing what was read gives
the same bytes again."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.measurement import MeasurementSet
from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.plugins.readers.ades_xml import AdesXmlReader
from cistrack.plugins.readers.csv_file import CsvReader
from cistrack.plugins.readers.mpc80 import Mpc80Reader
from cistrack.plugins.readers.tdm import TdmReader
from cistrack.astro.sites import Site, observatory
from cistrack.testing.checks_reader import EPOCH, sample_measurements
from cistrack.units import ARCSEC_RAD, TU_S

FORMATS = [(AdesPsvReader, ".psv"), (AdesXmlReader, ".xml"), (Mpc80Reader, ".obs"), (TdmReader, ".tdm"),
           (CsvReader, ".csv")]


def _kinds(cls):
    return [k for k in ("azel", "radec") if k in cls.measurement_kinds]


@pytest.mark.parametrize("cls, suffix", FORMATS, ids=[c.__name__ for c, _ in FORMATS])
def test_write_read_write_gives_the_same_bytes(tmp_path, cls, suffix):
    for kind in _kinds(cls):
        ms = sample_measurements(kind, n=40, seed=11)
        a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
        cls().write(a, ms, EPOCH)
        back = cls().read(a, EPOCH)
        cls().write(b, back, EPOCH)
        assert a.read_bytes() == b.read_bytes()
        assert np.max(np.abs(back.times - ms.times)) * TU_S <= cls.time_resolution_s / 2 + 1e-9


@pytest.mark.parametrize("cls, suffix", [f for f in FORMATS if f[0] is not Mpc80Reader],
                         ids=[c.__name__ for c, _ in FORMATS if c is not Mpc80Reader])
def test_angles_and_sigmas_come_back_bit_for_bit(tmp_path, cls, suffix):
    for kind in _kinds(cls):
        ms = sample_measurements(kind, n=200, seed=3)
        cls().write(tmp_path / f"x{suffix}", ms, EPOCH)
        back = cls().read(tmp_path / f"x{suffix}", EPOCH)
        assert np.array_equal(back.values, ms.values)
        assert np.array_equal(back.sigmas, ms.sigmas)
        assert back.sites.tolist() == ms.sites.tolist() and back.kinds.tolist() == ms.kinds.tolist()


def test_mpc80_rounds_to_a_millisecond_of_ra_and_a_hundredth_arcsec_of_dec(tmp_path):
    ms = sample_measurements("radec", n=300, seed=4)
    Mpc80Reader().write(tmp_path / "x.obs", ms, EPOCH)
    back = Mpc80Reader(sigma_arcsec=0.7).read(tmp_path / "x.obs", EPOCH)
    dra = ((back.values[:, 0] - ms.values[:, 0] + np.pi) % (2 * np.pi) - np.pi) / ARCSEC_RAD
    ddec = (back.values[:, 1] - ms.values[:, 1]) / ARCSEC_RAD
    assert np.max(np.abs(dra)) <= 0.0075 + 1e-9 and np.max(np.abs(ddec)) <= 0.005 + 1e-9
    assert np.max(np.abs(dra)) > 0.004  # really rounded, not exact
    assert np.all(back.sigmas[:, 1] == 0.7 * ARCSEC_RAD)   # on the sky: Dec, and RA x cos(Dec)
    np.testing.assert_allclose(back.sigmas[:, 0] * np.cos(back.values[:, 1]), 0.7 * ARCSEC_RAD, rtol=1e-15)


def _explicit_site_set(kind):
    ms = sample_measurements(kind, n=9)
    here = Site(30.618963, -96.339214, 103.8, name="TAMU")
    sites = np.where(np.arange(9) % 2 == 0, "TAMU", "711")
    return MeasurementSet(ms.times, ms.values, ms.sigmas, ms.names, {}, sites, ms.kinds,
                          {"TAMU": here, "711": observatory("711")})


@pytest.mark.parametrize("cls, suffix", [(AdesPsvReader, ".psv"), (AdesXmlReader, ".xml"), (TdmReader, ".tdm")])
def test_sites_given_by_coordinates_round_trip_without_a_sites_parameter(tmp_path, cls, suffix):
    ms = _explicit_site_set(_kinds(cls)[-1])
    cls().write(tmp_path / f"x{suffix}", ms, EPOCH)
    back = cls().read(tmp_path / f"x{suffix}", EPOCH)
    assert back.sites.tolist() == ms.sites.tolist()
    assert back.site_table["TAMU"].latitude_deg == 30.618963
    assert back.site_table["TAMU"].height_m == 103.8
    assert back.site_table["711"] == observatory("711")


def test_csv_and_mpc80_take_explicit_sites_from_the_reader_parameter(tmp_path):
    ms = _explicit_site_set("azel")
    CsvReader().write(tmp_path / "x.csv", ms, EPOCH)
    spec = {"TAMU": {"latitude_deg": 30.618963, "longitude_deg": -96.339214, "height_m": 103.8}}
    back = CsvReader(sites=spec).read(tmp_path / "x.csv", EPOCH)
    assert back.site_table["TAMU"].longitude_deg == -96.339214
    lines = (tmp_path / "x.csv").read_text()
    assert "TAMU" in lines


def test_tdm_keeps_az_el_and_ra_dec_from_several_stations_in_one_file(tmp_path):
    az = sample_measurements("azel", n=6, seed=1)
    rd = sample_measurements("radec", n=6, seed=2)
    times = np.concatenate([az.times, rd.times + 0.5 / TU_S])
    order = np.argsort(times)
    mixed = MeasurementSet(times[order], np.concatenate([az.values, rd.values])[order],
                           np.concatenate([az.sigmas, rd.sigmas])[order], ("angle_1", "angle_2"), {},
                           np.concatenate([az.sites, rd.sites])[order],
                           np.concatenate([az.kinds, rd.kinds])[order], az.site_table)
    TdmReader().write(tmp_path / "m.tdm", mixed, EPOCH)
    back = TdmReader().read(tmp_path / "m.tdm", EPOCH)
    assert back.kinds.tolist() == mixed.kinds.tolist() and back.sites.tolist() == mixed.sites.tolist()
    assert np.array_equal(back.values, mixed.values)
    assert back[0].names in (("azimuth", "elevation"), ("right_ascension", "declination"))


@pytest.mark.parametrize("cls", [AdesPsvReader, AdesXmlReader, Mpc80Reader])
def test_ra_dec_formats_refuse_to_write_az_el(tmp_path, cls):
    from cistrack.errors import MeasurementError
    with pytest.raises(MeasurementError, match="RA/Dec"):
        cls().write(tmp_path / "x", sample_measurements("azel"), EPOCH)


def test_ades_rms_ra_is_the_ra_sigma_times_cos_dec(tmp_path):
    ms = sample_measurements("radec", n=5)
    AdesPsvReader().write(tmp_path / "x.psv", ms, EPOCH)
    rows = [r.split("|") for r in (tmp_path / "x.psv").read_text().splitlines()[2:]]
    rms_ra = np.array([float(r[6]) for r in rows])
    assert np.allclose(rms_ra, ms.sigmas[:, 0] / ARCSEC_RAD * np.cos(ms.values[:, 1]), rtol=1e-12)
