"""Sky predictions (cistrack.fitting.sky_ephemeris): the Sun and Moon angles against astropy, the
sky ellipse against 2,000 orbits drawn from the covariance, the rates against the positions (up to
an impact), the times refused outside the ephemeris' years."""
import warnings

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.sites import observatory
from cistrack.errors import ConfigError, StateError
from cistrack.fitting.sky_ephemeris import CSV_COLUMNS, sky_ephemeris
from cistrack.plugin.registry import default_registry
from cistrack.results.estimates import KM_SCALE

EPOCH = "2026-03-01T00:00:00Z"
TRUTH_KM = np.array([392895.24, 0.0, -70018.76875739652, 0.0, -0.10597771954517338, 0.0])  # real-data truth


@pytest.fixture(scope="module")
def case():
    reg = default_registry()
    dyn = reg.create("dynamics", "ephemeris", epoch=EPOCH)
    x = TRUTH_KM / KM_SCALE
    cov = np.diag([9.0, 1.0, 2.0, 1e-10, 4e-10, 1e-10]) / np.outer(KM_SCALE, KM_SCALE)
    times = units.hours_to_tu(np.array([25.0, 28.0, 31.0]))
    return dyn, x, cov, times, sky_ephemeris(dyn, x, cov, 0.0, times, observatory("711"), EPOCH, reg)


def test_sun_and_moon_angles_agree_with_astropy(case):
    from astropy import units as u
    from astropy.coordinates import EarthLocation, SkyCoord, get_body
    from astropy.time import Time, TimeDelta

    _, _, _, times, sk = case
    site = observatory("711")
    loc = EarthLocation.from_geodetic(site.longitude_deg * u.deg, site.latitude_deg * u.deg, site.height_m * u.m)
    t = Time(EPOCH.replace("Z", ""), scale="utc") + TimeDelta(times * units.TU_S, format="sec")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sun = get_body("sun", t, loc)
        moon = get_body("moon", t, loc)                                   # seen from the site
        target = SkyCoord(ra=sk.ra_deg * u.deg, dec=sk.dec_deg * u.deg, frame=moon.frame.replicate_without_data())
        # astropy's bodies are apparent (aberration, deflection: < 30"); the target astrometric
        np.testing.assert_allclose(target.separation(sun).deg, sk.solar_elongation_deg, atol=0.02)
        np.testing.assert_allclose(target.separation(moon).deg, sk.lunar_distance_deg, atol=0.02)


def test_the_sky_ellipse_matches_sampled_orbits(case):
    dyn, x, cov, times, sk = case
    reg = default_registry()
    site = observatory("711")
    radec = reg.create("sensor", "real-telescope", measurement="radec", latitude_deg=site.latitude_deg,
                       longitude_deg=site.longitude_deg, height_m=site.height_m, epoch=EPOCH)
    draws = np.random.default_rng(4904).multivariate_normal(x, cov, size=2000)
    states = dyn.propagate(draws, 0.0, times).states                      # (K, N, 6)
    for k in range(times.size):
        z = radec.measure(states[k], times[k])
        d = np.stack([((z[:, 0] - np.radians(sk.ra_deg[k]) + np.pi) % (2 * np.pi) - np.pi) * np.cos(z[:, 1]),
                      z[:, 1] - np.radians(sk.dec_deg[k])], 1) * 206264.80624709636
        sample = np.cov(d.T)
        np.testing.assert_allclose(np.sqrt(np.linalg.eigvalsh(sample)), np.sqrt(np.linalg.eigvalsh(sk.covariance_arcsec2[k])),
                                   rtol=0.06)
        m2 = np.einsum("ni,ij,nj->n", d, np.linalg.inv(sk.covariance_arcsec2[k]), d)
        assert abs(np.mean(m2 <= 9.0) - 0.989) < 0.01                     # inside the 3-sigma ellipse


def test_the_rates_are_the_motion_between_neighbouring_predictions(case):
    dyn, x, cov, times, sk = case
    dt = units.seconds_to_tu(60.0)
    t = np.array([times[0] - dt, times[0] + dt])
    near = sky_ephemeris(dyn, x, cov, 0.0, t, observatory("711"), EPOCH)
    dra = (near.ra_deg[1] - near.ra_deg[0]) * np.cos(np.radians(sk.dec_deg[0])) * 3600.0 / 2.0
    ddec = (near.dec_deg[1] - near.dec_deg[0]) * 3600.0 / 2.0
    assert abs(dra - sk.ra_rate_arcsec_min[0]) < 0.01 and abs(ddec - sk.dec_rate_arcsec_min[0]) < 0.01


def test_rates_within_30_s_before_the_impact_are_the_motion_before_it(case):
    from cistrack.least_squares.events import first_impact

    dyn, x, cov, _, _ = case
    hit, body = first_impact(dyn, x, 0.0, units.days_to_tu(17.0))     # the truth hits the Moon on 2026-03-17
    assert body == "Moon"
    second = units.seconds_to_tu(1.0)
    t = np.array([hit - 20 * second, hit - 10 * second])               # their +30 s lies past the impact
    sk = sky_ephemeris(dyn, x, cov, 0.0, t, observatory("568"), EPOCH)
    dra = (sk.ra_deg[1] - sk.ra_deg[0]) * np.cos(np.radians(sk.dec_deg.mean())) * 3600.0 * 6.0
    ddec = (sk.dec_deg[1] - sk.dec_deg[0]) * 3600.0 * 6.0                # arcsec per minute over the 10 s
    assert abs(dra - sk.ra_rate_arcsec_min.mean()) < 0.05 and abs(ddec - sk.dec_rate_arcsec_min.mean()) < 0.05


@pytest.mark.parametrize("t", [1e9, -1e9, 1e4])
def test_times_outside_the_ephemeris_years_are_refused_naming_times(case, t):
    dyn, x, cov, _, _ = case
    with pytest.raises(StateError, match="times: .* outside the years 1900 to 2052"):
        sky_ephemeris(dyn, x, cov, 0.0, np.array([1.0, t]), observatory("568"), EPOCH)


def test_rows_and_csv_hold_every_column(case, tmp_path):
    sk = case[4]
    p = sk.write_csv(tmp_path / "sky.csv")
    lines = p.read_text().splitlines()
    assert lines[0].split(",") == list(CSV_COLUMNS) and len(lines) == 4
    a, b, pa = sk.ellipse()
    assert np.all(a >= b) and np.all((pa >= 0) & (pa < 180))
    assert np.all(sk.mahalanobis2(sk.ra_deg, sk.dec_deg) == 0.0)


def test_a_cr3bp_orbit_is_refused_naming_the_dynamics():
    dyn = default_registry().create("dynamics", "cr3bp")
    with pytest.raises(ConfigError, match="real Earth-Moon frame"):
        sky_ephemeris(dyn, np.r_[1.02, 0, -0.18, 0, -0.1, 0], np.eye(6) * 1e-12, 0.0, [0.1], observatory("711"), EPOCH)


@pytest.mark.parametrize("times", [["a"], "2026-03-01", [[1.0], [2.0, 3.0]]])
def test_times_that_are_not_numbers_are_refused_naming_times(case, times):
    """A list of strings had raised numpy's "could not convert string to float", naming nothing."""
    dyn, x, cov, _, _ = case
    with pytest.raises(StateError, match="times must be one or more finite numbers"):
        sky_ephemeris(dyn, x, cov, 0.0, times, observatory("568"), EPOCH)
