"""cistrack.astro.timescales: UTC/TAI/TT/TDB/UT1 offline, checked against closed forms and IERS facts."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from cistrack.astro import timescales as ts


def test_tai_minus_utc_counts_the_leap_seconds_in_force():
    assert ts.tai_minus_utc("2000-01-01T00:00:00Z") == 32.0
    assert ts.tai_minus_utc("2012-06-30T23:59:59Z") == 34.0
    assert ts.tai_minus_utc("2012-07-01T00:00:01Z") == 35.0
    assert ts.tai_minus_utc("2020-01-01T00:00:00Z") == 37.0


def test_no_leap_seconds_are_invented_after_the_table():
    assert ts.tai_minus_utc("2050-06-01T00:00:00Z") == 37.0


def test_tt_is_tai_plus_32_184_seconds():
    a1, a2 = ts.tai_jd("2031-05-06T07:08:09Z", np.array([0.0, 1e5]))
    t1, t2 = ts.tt_jd("2031-05-06T07:08:09Z", np.array([0.0, 1e5]))
    np.testing.assert_allclose(((t1 - a1) + (t2 - a2)) * 86400.0, 32.184, atol=1e-6)


def test_utc_of_j2000_tt_gives_tdb_seconds_near_zero():
    # J2000.0 = 2000-01-01T12:00:00 TT = 11:58:55.816 UTC; TDB - TT there is about
    # 0.001657 sin(357.53 deg) s (Fairhead-Bretagnon leading term) = -71 us.
    s = ts.tdb_seconds_since_j2000("2000-01-01T11:58:55.816Z")
    assert abs(s - 0.001657 * np.sin(np.radians(357.53))) < 5e-5


@pytest.mark.parametrize("year", [2000, 2013, 2026, 2039, 2050])
def test_tdb_minus_tt_follows_the_leading_periodic_term(year):
    epoch = f"{year}-03-01T00:00:00Z"
    secs = np.linspace(0.0, 365.25 * 86400.0, 9)
    t1, t2 = ts.tt_jd(epoch, secs)
    b1, b2 = ts.tdb_jd(epoch, secs)
    d = ((b1 - t1) + (b2 - t2)) * 86400.0
    g = np.radians(357.53 + 0.98560028 * ((t1 - 2451545.0) + t2))
    np.testing.assert_allclose(d, 0.001657 * np.sin(g), atol=5e-5)


def test_seconds_after_the_epoch_are_elapsed_si_seconds_across_a_leap_second():
    # 2016-12-31T23:59:60 was a leap second: 2 elapsed seconds after 23:59:59 is 00:00:00 UTC.
    t = ts.utc_time("2016-12-31T23:59:59Z", 2.0)
    assert t.utc.isot == "2017-01-01T00:00:00.000000000"


def test_tdb_jd_is_vectorised_over_seconds():
    j1, j2 = ts.tdb_jd("2026-01-01T00:00:00Z", np.arange(5) * 3600.0)
    assert j1.shape == j2.shape == (5,)
    np.testing.assert_allclose(np.diff((j1 - 2461041.0) + j2) * 24.0, 1.0, atol=1e-9)


def test_ut1_minus_utc_comes_from_the_bundled_table_inside_it():
    # IERS Bulletin B: UT1-UTC on 2020-01-01 was -0.1772 s (to 1 ms).
    eo = ts.earth_orientation("2020-01-01T00:00:00Z")
    assert bool(eo.tabulated)
    assert abs(float(eo.ut1_minus_utc) - (-0.1772)) < 2e-3


def test_ut1_minus_utc_stays_below_0_9_seconds_by_definition_of_utc():
    eo = ts.earth_orientation("2000-01-01T00:00:00Z", np.linspace(0, 27 * 365.25 * 86400, 200))
    assert np.all(np.abs(eo.ut1_minus_utc) < 0.9)


def test_outside_the_table_the_fallback_is_zero_ut1_utc_and_the_mean_pole():
    eo = ts.earth_orientation("2045-01-01T00:00:00Z")
    assert not bool(eo.tabulated)
    assert float(eo.ut1_minus_utc) == 0.0
    arcsec = np.pi / 648000.0
    np.testing.assert_allclose([float(eo.xp), float(eo.yp)], np.array(ts.MEAN_POLE_ARCSEC) * arcsec)


def test_ut1_jd_differs_from_utc_by_ut1_minus_utc():
    epoch = "2021-07-01T00:00:00Z"
    eo = ts.earth_orientation(epoch)
    u1, u2 = ts.ut1_jd(epoch, 0.0, eo)
    assert abs(((u1 - 2459396.5) + u2) * 86400.0 - float(eo.ut1_minus_utc)) < 1e-6


def test_a_malformed_epoch_is_refused_with_its_text():
    with pytest.raises(ValueError, match="not-a-time"):
        ts.tdb_jd("not-a-time")


def test_non_finite_seconds_are_refused():
    with pytest.raises(ValueError, match="NaN"):
        ts.tdb_jd("2026-01-01T00:00:00Z", np.array([0.0, np.nan]))


def test_conversions_work_with_the_network_unreachable():
    # A fresh interpreter in which every socket connection fails loudly: the conversions must
    # still work from bundled data, for dates inside and far outside the IERS tables, also
    # years after the bundled tables were made (astropy's clock is moved to 2040).
    code = textwrap.dedent("""
        import socket
        from astropy.time import Time
        Time.now = classmethod(lambda cls: Time("2040-01-01T00:00:00", scale="utc"))
        def refuse(*a, **k):
            raise RuntimeError("network access attempted")
        socket.socket.connect = refuse
        socket.create_connection = refuse
        import numpy as np
        from cistrack import timescales as ts
        for epoch in ("2000-01-01T00:00:00Z", "2026-06-01T00:00:00Z", "2050-12-31T00:00:00Z"):
            ts.tdb_jd(epoch, np.array([0.0, 86400.0]))
            ts.ut1_jd(epoch, 0.0)
            ts.earth_orientation(epoch)
        print("offline-ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "offline-ok" in out.stdout


def test_time_scales_gives_the_same_numbers_as_the_single_conversions():
    epoch, secs = "2024-02-29T12:00:00Z", np.array([0.0, 3.7e5, 9.9e7])
    s = ts.time_scales(epoch, secs)
    for got, want in ((s.tt, ts.tt_jd(epoch, secs)), (s.tdb, ts.tdb_jd(epoch, secs)),
                      (s.ut1, ts.ut1_jd(epoch, secs))):
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    np.testing.assert_array_equal(s.orientation.xp, ts.earth_orientation(epoch, secs).xp)
