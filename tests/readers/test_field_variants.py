"""Files as the field writes them (not by cistrack's writers) read correctly."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.plugins.readers.mpc80 import Mpc80Reader
from cistrack.plugins.readers.tdm import TdmReader
from cistrack.units import ARCSEC_RAD, TU_S

EPOCH = "2026-03-01T00:00:00Z"

PSV = """# version=2017
# observatory
! mpcCode 705
# submitter
! name J. Observer
permID |provID     |trkSub  |mode|stn |obsTime                 |ra         |dec        |rmsRA|rmsDec|astCat|mag  |band
       |           |CIS01   | CCD|705 |2026-03-01T03:40:00.123Z|101.234567 |-12.345678 | 0.45| 0.50 |Gaia2 |17.2 |G
# observatory
! mpcCode 711
permID |provID     |trkSub  |mode|stn |obsTime                 |ra         |dec        |astCat
       |           |CIS01   | CCD|711 |2026-03-01T04:20:00Z    |101.5      |-12.5      |Gaia2
"""


PSV_COMMENTED = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
CIS01|CCD|705|2026-03-01T03:40:00Z|101.2|-12.3|0.5|0.5|Gaia3
{comment}
CIS01|CCD|705|2026-03-01T03:50:00Z|101.3|-12.4|0.5|0.5|Gaia3
"""


@pytest.mark.parametrize("comment", ["# mid comment", "! line note", "# mid comment\n"])
def test_ades_psv_comment_lines_between_data_rows_are_read_past(tmp_path, comment):
    """The data row after a comment had been refused as a field-name line that lacks dec, obsTime,
    ra and stn (probe I7)."""
    p = tmp_path / "commented.psv"
    p.write_text(PSV_COMMENTED.format(comment=comment))
    assert len(AdesPsvReader().read(p, EPOCH)) == 2


def test_ades_psv_with_observatory_blocks_padding_and_a_second_header(tmp_path):
    p = tmp_path / "field.psv"
    p.write_text(PSV)
    ms = AdesPsvReader(sigma_arcsec=2.0).read(p, EPOCH)
    assert ms.sites.tolist() == ["705", "711"]
    assert ms.times[0] * TU_S == pytest.approx(3 * 3600 + 40 * 60 + 0.123, abs=1e-6)
    assert ms.values[0, 0] == pytest.approx(math.radians(101.234567), abs=1e-15)
    assert ms.sigmas[0, 0] == pytest.approx(0.45 * ARCSEC_RAD / math.cos(math.radians(-12.345678)), rel=1e-12)
    assert ms.sigmas[1, 1] == pytest.approx(2.0 * ARCSEC_RAD)    # no rmsDec: the reader's default


MPC = ("     K26A01A*KC2026 03 01.15278 06 44 56.296-12 20 44.44         17.2 G      705\n"
       "     K26A01A  C2026 03 01.18056 06 46 00.000-12 30 00.0          17.3 G      711\n")


def test_mpc80_with_discovery_asterisk_magnitudes_and_short_fractions(tmp_path):
    p = tmp_path / "field.obs"
    p.write_text(MPC)
    ms = Mpc80Reader().read(p, EPOCH)
    assert ms.sites.tolist() == ["705", "711"]
    assert ms.times[0] * TU_S == pytest.approx(0.15278 * 86400, abs=1e-3)
    ra = (6 + 44 / 60 + 56.296 / 3600) * 15
    assert ms.values[0, 0] == pytest.approx(math.radians(ra), abs=1e-14)
    assert ms.values[1, 1] == pytest.approx(math.radians(-(12 + 30 / 60)), abs=1e-14)


TDM = """CCSDS_TDM_VERS = 2.0
COMMENT written by another system
CREATION_DATE = 2026-061T00:00:00
ORIGINATOR = SOMEONE
META_START
COMMENT angles of a cislunar object
TIME_SYSTEM = UTC
PARTICIPANT_1 = 711
PARTICIPANT_2 = CIS01
MODE = SEQUENTIAL
PATH = 2,1
ANGLE_TYPE = RADEC
REFERENCE_FRAME = EME2000
META_STOP
DATA_START
ANGLE_1 = 2026-060T03:40:00.5 101.25
ANGLE_2 = 2026-060T03:40:00.5 -12.5
DATA_STOP
"""


def test_tdm_with_day_of_year_epochs_and_comments(tmp_path):
    p = tmp_path / "field.tdm"
    p.write_text(TDM)
    ms = TdmReader(sigma_arcsec=0.8).read(p, "2026-03-01T00:00:00Z")
    assert ms.times[0] * TU_S == pytest.approx(3 * 3600 + 40 * 60 + 0.5, abs=1e-6)   # day 60 = 1 March
    np.testing.assert_allclose(ms.values[0], np.radians([101.25, -12.5]), atol=1e-15)
    # the default applies on the sky: 0.8 arcsec on RA x cos(Dec), so 0.8 / cos(Dec) on RA
    assert ms.sigmas[0, 0] == pytest.approx(0.8 * ARCSEC_RAD / np.cos(np.radians(-12.5)), rel=1e-15)
    assert ms.sigmas[0, 1] == pytest.approx(0.8 * ARCSEC_RAD, rel=1e-15) and ms.kinds[0] == "radec"
