"""Weights on the sky (issue 32, item 3): every reader applies its default sigma to Dec and to
RA x cos(Dec), as ADES's rmsRA is stated, and a run says in its log when the default applies."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.plugin.registry import default_registry
from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.plugins.readers.mpc80 import Mpc80Reader
from cistrack.plugins.readers.tdm import TdmReader
from cistrack.runs.run_inputs import read_scenario_observations
from cistrack.scenario.loading import load_scenario
from cistrack.units import ARCSEC_RAD

EPOCH = "2026-03-01T00:00:00Z"


def _mpc80_line(dec_text: str, day: str = "01.500000", code: str = "568") -> str:
    return f"{'':5}{'cis0001':<7}  C2026 03 {day}10 00 00.000{dec_text}{'':21}{code}"


def test_mpc80_sigma_is_on_ra_times_cos_dec_at_dec_60(tmp_path):
    p = tmp_path / "obs.obs"
    p.write_text(_mpc80_line("+60 00 00.00") + "\n")
    ms = Mpc80Reader(sigma_arcsec=0.5).read(p, EPOCH)
    assert ms.values[0, 1] == pytest.approx(math.radians(60.0), abs=1e-15)
    # closed form: 0.5 arcsec on RA x cos(60 deg) is 1.0 arcsec on RA itself; Dec keeps 0.5
    assert ms.sigmas[0, 0] / ARCSEC_RAD == pytest.approx(1.0, rel=1e-14)
    assert ms.sigmas[0, 1] / ARCSEC_RAD == pytest.approx(0.5, rel=1e-15)


def test_ades_default_for_a_record_without_rms_is_on_the_sky_like_rmsra(tmp_path):
    p = tmp_path / "obs.psv"
    p.write_text("# version=2017\n"
                 "trkSub |mode|stn |obsTime                 |ra         |dec        |rmsRA|rmsDec|astCat\n"
                 "cis0001|CCD |568 |2026-03-01T04:20:00.000Z|150.0      |60.0       |0.5  |0.5   |Gaia3\n"
                 "cis0001|CCD |568 |2026-03-01T04:30:00.000Z|150.0      |60.0       |     |      |Gaia3\n")
    ms = AdesPsvReader(sigma_arcsec=0.5).read(p, EPOCH)
    np.testing.assert_allclose(ms.sigmas / ARCSEC_RAD, [[1.0, 0.5], [1.0, 0.5]], rtol=1e-14)
    assert (ms.meta["default_sigma_count"], ms.meta["default_sigma_arcsec"]) == (1, 0.5)


def _tdm(path, sigma_comment: str = "") -> None:
    path.write_text("CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = test\n\n"
                    f"META_START\n{sigma_comment}TIME_SYSTEM = UTC\nPARTICIPANT_1 = 568\nPARTICIPANT_2 = cis0001\n"
                    "ANGLE_TYPE = RADEC\nREFERENCE_FRAME = ICRF\nMETA_STOP\n\nDATA_START\n"
                    "ANGLE_1 = 2026-03-01T04:20:00.000 150.0\nANGLE_2 = 2026-03-01T04:20:00.000 60.0\n"
                    "ANGLE_1 = 2026-03-02T04:20:00.000 151.0\nANGLE_2 = 2026-03-02T04:20:00.000 -60.0\n"
                    "DATA_STOP\n")


def test_tdm_sigma_comment_for_radec_is_on_the_sky(tmp_path):
    p = tmp_path / "obs.tdm"
    _tdm(p, "COMMENT cistrack sigma_arcsec ANGLE_1=0.5 ANGLE_2=0.25\n")
    ms = TdmReader().read(p, EPOCH)
    np.testing.assert_allclose(ms.sigmas / ARCSEC_RAD, [[1.0, 0.25], [1.0, 0.25]], rtol=1e-14)
    assert ms.meta["default_sigma_count"] == 0


def test_tdm_default_is_one_arcsec_on_the_sky(tmp_path):
    p = tmp_path / "obs.tdm"
    _tdm(p)
    ms = TdmReader().read(p, EPOCH)
    np.testing.assert_allclose(ms.sigmas / ARCSEC_RAD, [[2.0, 1.0], [2.0, 1.0]], rtol=1e-14)
    assert (ms.meta["default_sigma_count"], ms.meta["default_sigma_arcsec"]) == (2, 1.0)


def test_a_tdm_written_from_a_set_with_sky_sigmas_reads_back_bit_for_bit_in_one_segment(tmp_path):
    p = tmp_path / "obs.tdm"
    _tdm(p)
    ms = TdmReader().read(p, EPOCH)
    TdmReader().write(tmp_path / "copy.tdm", ms, EPOCH)
    text = (tmp_path / "copy.tdm").read_text()
    assert text.count("META_START") == 1 and "ANGLE_1=1.000000000000 ANGLE_2=1.000000000000" in text
    back = TdmReader(sigma_arcsec=7.0).read(tmp_path / "copy.tdm", EPOCH)
    assert np.array_equal(back.sigmas, ms.sigmas) and np.array_equal(back.values, ms.values)


def _said_reading_tdm(tmp_path) -> list[str]:
    """What a real-data run says as it reads a TDM file without uncertainties."""
    p = tmp_path / "obs.tdm"
    _tdm(p)
    scen = load_scenario("real-data").with_overrides({"measurements": {"file": str(p), "reader": {"name": "tdm"}}})
    reg = default_registry()
    said: list[str] = []
    read_scenario_observations(scen, scen.build("sensor", reg), reg, said.append)
    return said


def test_a_run_on_a_tdm_without_uncertainties_prints_the_default_it_applies(tmp_path):
    said = _said_reading_tdm(tmp_path)
    line = next(s for s in said if s.startswith("weights:"))
    assert "2 of 2 observations have no uncertainty in the file" in line
    assert "tdm reader's default sigma_arcsec = 1 arcsec on the sky" in line


def _said_reading_ades(p) -> list[str]:
    """What a real-data run says as it reads the ADES PSV file ``p``."""
    scen = load_scenario("real-data").with_overrides({"measurements": {"file": str(p), "reader": {"name": "ades-psv"}}})
    reg = default_registry()
    said: list[str] = []
    read_scenario_observations(scen, scen.build("sensor", reg), reg, said.append)
    return said


def test_a_run_on_ades_with_its_own_uncertainties_says_it_uses_them(tmp_path):
    p = tmp_path / "obs.psv"
    p.write_text("# version=2017\n"
                 "trkSub |mode|stn |obsTime                 |ra         |dec        |rmsRA|rmsDec|astCat\n"
                 "cis0001|CCD |568 |2026-03-01T04:20:00.000Z|150.0      |60.0       |0.5  |0.5   |Gaia3\n")
    assert "weights: the file's own uncertainties for all 1 observations" in _said_reading_ades(p)


def test_a_run_on_ades_with_rmsra_but_no_rmsdec_says_the_file_gives_one_angle_and_the_default_the_other(tmp_path):
    p = tmp_path / "obs.psv"
    p.write_text("# version=2017\n"
                 "trkSub |mode|stn |obsTime                 |ra         |dec        |rmsRA|astCat\n"
                 "cis0001|CCD |568 |2026-03-01T04:20:00.000Z|150.0      |60.0       |0.5  |Gaia3\n"
                 "cis0001|CCD |568 |2026-03-01T04:30:00.000Z|150.1      |60.1       |0.5  |Gaia3\n")
    line = next(s for s in _said_reading_ades(p) if s.startswith("weights:"))
    assert "2 of 2 observations state the uncertainty of one angle only" in line
    assert "have no uncertainty" not in line


def test_the_real_telescope_simulates_radec_noise_on_the_sky():
    reg = default_registry()
    sensor = reg.create("sensor", "real-telescope", measurement="radec", sigma_arcsec=0.5, epoch=EPOCH)
    x = np.array([[0.9, 0.1, 0.3, 0.0, 0.1, 0.0], [1.0, -0.2, -0.5, 0.0, 0.1, 0.0]])
    z = sensor.measure(x, 0.1)
    s = sensor.sigmas(x, 0.1)
    np.testing.assert_allclose(s[:, 0] * np.cos(z[:, 1]) / ARCSEC_RAD, 0.5, rtol=1e-14)
    np.testing.assert_allclose(s[:, 1] / ARCSEC_RAD, 0.5, rtol=1e-15)


def test_a_run_on_cistrack_fit_s_own_copy_of_the_observations_says_nothing_of_their_weights(tmp_path):
    """The copy holds the default filled in; its weights were told of the user's file (probe H12)."""
    from cistrack.runs.run_inputs import reading_own_copies

    with reading_own_copies():
        said = _said_reading_tdm(tmp_path)
    assert said and not [s for s in said if s.startswith("weights:")]
    assert [s for s in _said_reading_tdm(tmp_path) if s.startswith("weights:")]  # and outside it, as before
