"""Impacts and closest approaches (cistrack.least_squares.events): the impact time against an
independent tighter integration with its own surface-crossing event, the 1-sigma of every value
against 200 orbits drawn from the covariance, the lunar frame against the Moon's libration."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack import units
from cistrack.astro.ephemeris import de421
from cistrack.least_squares.body_fixed import selenographic
from cistrack.least_squares.events import event_values, orbit_events
from cistrack.plugin.registry import default_registry

KM = np.r_[[units.LU_KM] * 3, [units.VU_KMS] * 3]


@pytest.fixture(scope="module")
def dyn():
    return default_registry().create("dynamics", "ephemeris", epoch="2026-03-01T00:00:00Z")


def _towards_moon(dyn, offset_km, rel_v_kms):
    """Synodic state at t = 0 of a point ``offset_km`` from the Moon moving at ``rel_v_kms`` relative to it."""
    fr = dyn.frame
    m, mv = fr.ephemeris.moon(*fr.epoch_tdb)
    return fr.gcrs_to_synodic(np.concatenate([m + offset_km, mv + rel_v_kms]), 0.0)


def _cov(pos_km, vel_kms):
    return np.diag(np.r_[[pos_km ** 2] * 3, [vel_kms ** 2] * 3]) / KM ** 2


@pytest.fixture(scope="module")
def impact_case(dyn):
    off = np.array([20000.0, 5000.0, 3000.0])
    x = _towards_moon(dyn, off, -off / np.linalg.norm(off) + np.array([0.0, 0.05, 0.0]))
    return x, _cov(1.0, 1e-3)


def test_the_impact_time_agrees_with_a_tighter_independent_integration(dyn, impact_case):
    x, _ = impact_case
    [ev] = [e for e in orbit_events(dyn, x, None, 0.0, units.days_to_tu(2.0)) if e.kind == "impact"]
    radius = dyn.primary("Moon").radius

    def surface(t, y):
        return np.linalg.norm(y[:3] - dyn.frame.moon_synodic(t)[0]) - radius
    surface.terminal = True
    sol = solve_ivp(lambda t, y: dyn.derivatives(t, y[None])[0], (0.0, 1.0), x, method="DOP853", rtol=1e-13,
                    atol=1e-15, events=surface)
    assert abs(sol.t_events[0][0] - ev.t_tu) * units.TU_S < 1e-3          # seconds
    assert ev.altitude_km == 0.0 and ev.body == "Moon" and ev.utc.startswith("2026-03-01T04")


def test_the_descent_through_an_altitude_agrees_with_a_tighter_integration_and_sampling(dyn, impact_case):
    x, cov = impact_case
    evs = orbit_events(dyn, x, cov, 0.0, units.days_to_tu(2.0), approaches=False, altitude=("Moon", 100.0))
    [ev] = [e for e in evs if e.kind == "altitude 100 km"]
    radius = dyn.primary("Moon").radius + 100.0 / units.LU_KM

    def level(t, y):
        return np.linalg.norm(y[:3] - dyn.frame.moon_synodic(t)[0]) - radius
    level.terminal = True
    sol = solve_ivp(lambda t, y: dyn.derivatives(t, y[None])[0], (0.0, 1.0), x, method="DOP853", rtol=1e-13,
                    atol=1e-15, events=level)
    assert abs(sol.t_events[0][0] - ev.t_tu) * units.TU_S < 1e-3 and abs(ev.altitude_km - 100.0) < 1e-4
    std = _sampled_std(dyn, x, cov, "altitude 100 km", (0.0, units.days_to_tu(2.0)))
    lin = [ev.sigma[k] for k in ("time_s", "latitude_deg", "longitude_deg")] + [ev.sigma["speed_kms"]]
    np.testing.assert_allclose(lin, std[[0, 1, 2, 4]], rtol=0.15)


def _sampled_std(dyn, x, cov, kind, window, n=200, seed=4901):
    draws = np.random.default_rng(seed).multivariate_normal(x, cov, size=n)
    vals = event_values(dyn, draws, 0.0, kind, "Moon", window)
    assert np.all(np.isfinite(vals[:, 0]))
    vals[:, 0] *= units.TU_S
    return np.std(vals, axis=0, ddof=1)


def test_the_impact_sigma_matches_sampling_the_covariance(dyn, impact_case):
    x, cov = impact_case
    [ev] = orbit_events(dyn, x, cov, 0.0, units.days_to_tu(2.0), approaches=False)
    std = _sampled_std(dyn, x, cov, "impact", (0.0, units.days_to_tu(2.0)))
    lin = [ev.sigma[k] for k in ("time_s", "latitude_deg", "longitude_deg")] + [ev.sigma["speed_kms"]]
    np.testing.assert_allclose(lin, std[[0, 1, 2, 4]], rtol=0.15)           # 200 draws: ~5 % scatter


def test_a_flyby_is_a_closest_approach_with_sampled_sigma(dyn):
    off = np.array([20000.0, 0.0, 0.0])
    x = _towards_moon(dyn, off, np.array([-1.0, 0.25, 0.1]))
    cov = _cov(0.5, 2e-4)
    evs = [e for e in orbit_events(dyn, x, cov, 0.0, units.days_to_tu(1.0)) if e.body == "Moon"]
    [ev] = evs
    assert ev.kind == "closest approach" and 100.0 < ev.altitude_km < 20000.0
    window = (ev.t_tu - units.hours_to_tu(1.0), ev.t_tu + units.hours_to_tu(1.0))
    std = _sampled_std(dyn, x, cov, "closest approach", window)
    lin = [ev.sigma[k] for k in ("time_s", "latitude_deg", "longitude_deg", "altitude_km", "speed_kms")]
    np.testing.assert_allclose(lin, std, rtol=0.15)


def test_the_approach_is_the_minimum_of_a_finely_sampled_distance(dyn):
    x = _towards_moon(dyn, np.array([20000.0, 0.0, 0.0]), np.array([-1.0, 0.25, 0.1]))
    [ev] = [e for e in orbit_events(dyn, x, None, 0.0, units.days_to_tu(1.0)) if e.body == "Moon"]
    t = ev.t_tu + np.linspace(-60.0, 60.0, 241) / units.TU_S               # every 0.5 s
    s = dyn.propagate(x[None], 0.0, t).states[:, 0]
    d = np.linalg.norm(s[:, :3] - dyn.frame.moon_synodic(t), axis=1) * units.LU_KM - 1737.4
    assert abs(t[np.argmin(d)] - ev.t_tu) * units.TU_S <= 0.5
    assert abs(d.min() - ev.altitude_km) < 1e-3


def test_the_sub_earth_point_stays_within_the_moons_optical_libration():
    jd = 2461100.5 + np.arange(0.0, 60.0, 0.5)
    moon, _ = de421().moon(jd)
    lat, lon = selenographic(-moon, jd)
    assert np.max(np.abs(lat)) < 7.0 and np.max(np.abs(lon)) < 8.5          # libration +-6.7, +-7.9 deg
    assert np.max(np.abs(lat)) > 5.0 and np.max(np.abs(lon)) > 4.0
    assert abs(np.mean(lat)) < 1.0 and abs(np.mean(lon)) < 1.5


def test_bad_times_are_refused(dyn, impact_case):
    from cistrack.errors import StateError
    with pytest.raises(StateError, match="t_end > t0"):
        orbit_events(dyn, impact_case[0], None, 1.0, 0.5)


def test_a_prediction_across_the_impact_ends_there(dyn, impact_case):
    from cistrack.least_squares.events import times_until_impact
    from cistrack.least_squares.trajectory import arc_states

    x, _ = impact_case
    grid = units.hours_to_tu(np.arange(0.0, 24.0, 1.0 / 6.0))
    kept, hit = times_until_impact(dyn, x, 0.0, grid)
    assert hit is not None and hit[1] == "Moon" and kept[-1] < hit[0] and kept.size < grid.size
    assert (hit[0] - kept[-1]) * units.TU_S < 0.01 and np.all(kept[:-1] == grid[:kept.size - 1])
    end = arc_states(dyn, x, 0.0, kept)[-1]                               # propagates without a hit
    altitude = np.linalg.norm(end[:3] - dyn.frame.moon_synodic(kept[-1])[0]) * units.LU_KM - 1737.4
    assert 0.0 < altitude < 0.01                                          # km: within metres of the surface
    assert times_until_impact(dyn, x, 0.0, grid[:6]) == (pytest.approx(grid[:6]), None)


def test_a_prediction_can_end_at_a_chosen_altitude(dyn, impact_case):
    from types import SimpleNamespace

    from cistrack.least_squares.events import prediction_end

    x, cov = impact_case
    fit = SimpleNamespace(state=x, covariance=cov, epoch=0.0)                # what prediction_end reads of a fit
    grid = units.hours_to_tu(np.arange(0.0, 24.0, 1.0 / 6.0))
    kept, ev = prediction_end(dyn, fit, grid, altitude=("Moon", 500.0))
    assert ev.kind == "altitude 500 km" and kept[-1] == ev.t_tu and np.all(np.diff(kept) > 0)
    kept2, impact = prediction_end(dyn, fit, grid)
    assert impact.kind == "impact" and kept2[-1] > kept[-1]


def test_geodetic_coordinates_agree_with_astropy():
    import warnings

    from astropy import units as u
    from astropy.coordinates import GCRS, ITRS, CartesianRepresentation
    from astropy.time import Time, TimeDelta

    from cistrack.least_squares.body_fixed import geodetic

    r = np.random.default_rng(4902).normal(size=(5, 3))
    r = 6378.137 * r / np.linalg.norm(r, axis=1)[:, None]
    seconds = np.linspace(0.0, 86400.0 * 3, 5)
    lat, lon, h = geodetic(r, units.parse_utc("2026-03-01T00:00:00Z"), seconds)
    t = Time("2026-03-01T00:00:00", scale="utc") + TimeDelta(seconds, format="sec")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        itrs = GCRS(CartesianRepresentation(r.T * u.km), obstime=t).transform_to(ITRS(obstime=t))
        loc = itrs.earth_location.to_geodetic("WGS84")
    np.testing.assert_allclose(lat, loc.lat.deg, atol=1e-6)
    np.testing.assert_allclose(lon, loc.lon.deg, atol=1e-6)
    np.testing.assert_allclose(h, loc.height.to_value(u.km), atol=1e-4)


def _iau_moon(jd):
    """ICRF -> Moon body-fixed rotation of the IAU WGCCRE model (Archinal et al. 2011), an
    approximation of the mean-Earth frame: an independent check of the librations' convention and
    of the principal-axis -> mean-Earth rotation's sign."""
    def r1(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[1, 0, 0], [0, c, s], [0, -s, c]])

    def r3(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    d = jd - 2451545.0
    t = d / 36525.0
    e = np.radians(np.array([125.045 - 0.0529921 * d, 250.089 - 0.1059842 * d, 260.008 + 13.0120009 * d,
                             176.625 + 13.3407154 * d, 357.529 + 0.9856003 * d, 311.589 + 26.4057084 * d,
                             134.963 + 13.0649930 * d, 276.617 + 0.3287146 * d, 34.226 + 1.7484877 * d,
                             15.134 - 0.1589763 * d, 119.743 + 0.0036096 * d, 239.961 + 0.1643573 * d,
                             25.053 + 12.9590088 * d]))
    s, c = np.sin(e), np.cos(e)
    a0 = (269.9949 + 0.0031 * t - 3.8787 * s[0] - 0.1204 * s[1] + 0.0700 * s[2] - 0.0172 * s[3] + 0.0072 * s[5]
          - 0.0052 * s[9] + 0.0043 * s[12])
    d0 = (66.5392 + 0.0130 * t + 1.5419 * c[0] + 0.0239 * c[1] - 0.0278 * c[2] + 0.0068 * c[3] - 0.0029 * c[5]
          + 0.0009 * c[6] + 0.0008 * c[9] - 0.0009 * c[12])
    w = (38.3213 + 13.17635815 * d - 1.4e-12 * d * d + 3.5610 * s[0] + 0.1208 * s[1] - 0.0642 * s[2] + 0.0158 * s[3]
         + 0.0252 * s[4] - 0.0066 * s[5] - 0.0047 * s[6] - 0.0046 * s[7] + 0.0028 * s[8] + 0.0052 * s[9]
         + 0.0040 * s[10] + 0.0019 * s[11] - 0.0044 * s[12])
    return r3(np.radians(w)) @ r1(np.radians(90 - d0)) @ r3(np.radians(90 + a0))


def test_the_mean_earth_frame_agrees_with_the_iau_moon_model_and_not_with_the_principal_axes():
    from cistrack.least_squares.body_fixed import moon_me_rotation

    jd = 2461100.5 + np.linspace(0.0, 365.0, 40)
    m = moon_me_rotation(jd)
    off = [np.degrees(np.arccos((np.trace(m[k] @ _iau_moon(jd[k]).T) - 1) / 2)) * 3600 for k in range(jd.size)]
    assert max(off) < 20.0                                                 # arcsec: 170 m on the surface
    assert min(off) > 0.1                                                  # two different models


def test_event_lines_fit_in_120_columns_and_json(dyn, impact_case):
    import json

    from cistrack.least_squares.events import event_lines

    x, cov = impact_case
    evs = orbit_events(dyn, x, cov, 0.0, units.days_to_tu(2.0))
    lines = event_lines(evs, 2.0)
    assert all(len(line) <= 120 for line in lines) and "impact (Moon)" in "\n".join(lines)
    assert json.loads(json.dumps([e.as_dict() for e in evs]))[-1]["sigma"]["time_s"] > 0
    assert event_lines([], 2.0) == ["  no impact and no closest approach within 2 days of the fit epoch"]
