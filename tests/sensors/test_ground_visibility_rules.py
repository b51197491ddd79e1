"""Ground telescopes judged like space ones: the ``visibility`` rules are off by default and,
when given, the darkness rule agrees with astropy's Sun."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.testing.fixtures import lunar_distance_states
from cistrack.units import TU_S

LAT, LON, H = 30.618963, -96.339214, 103.8


def _astropy_sun_altitude(hours: np.ndarray) -> np.ndarray:
    from astropy.utils import iers
    iers.conf.auto_download = False
    import astropy.units as u
    from astropy.coordinates import AltAz, EarthLocation, get_sun
    from astropy.time import Time
    t = Time("2026-01-01T00:00:00", scale="utc") + hours * u.hour
    loc = EarthLocation(lat=LAT * u.deg, lon=LON * u.deg, height=H * u.m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return get_sun(t).transform_to(AltAz(obstime=t, location=loc)).alt.deg


def _overhead(sensor: GroundTelescope, t: np.ndarray) -> np.ndarray:
    """Synodic states (K, 6) 0.3 LU straight above the site at times t (K,)."""
    up = np.stack([sensor._affine(np.array([s]))[0][0, 2, :] for s in t])
    return np.concatenate([sensor.observer_position(t) + 0.3 * up, np.zeros((t.size, 3))], axis=1)


def test_default_ground_telescope_sees_by_elevation_alone():
    plain = GroundTelescope()
    x, t = lunar_distance_states(6), np.linspace(0.0, 0.3, 6)
    neu = plain.topocentric(x, t)
    expected = np.degrees(np.arctan2(neu[:, 2], np.hypot(neu[:, 0], neu[:, 1]))) >= 10.0
    assert not plain._rules.active and np.array_equal(plain.visible(x, t), expected)


def test_darkness_rule_agrees_with_astropy_sun_altitude():
    hours = np.linspace(0.0, 48.0, 193)
    t = hours * 3600.0 / TU_S
    dark = GroundTelescope(visibility={"sun_max_elevation_deg": -12.0})
    seen = dark.visible(_overhead(dark, t), t)
    alt = _astropy_sun_altitude(hours)
    clear = np.abs(alt + 12.0) > 1.0          # the idealised frame model is good to ~1 deg here
    assert clear.sum() > 150
    assert np.array_equal(seen[clear], alt[clear] <= -12.0)


def test_real_telescope_darkness_rule_agrees_with_astropy_sun_altitude():
    from cistrack.plugins.sensors.real_telescope import RealTelescope
    sensor = RealTelescope(visibility={"sun_max_elevation_deg": -6.0})
    hours = np.linspace(0.0, 24.0, 97)
    t = hours * 3600.0 / TU_S
    obs = sensor._observer.state(t * TU_S)
    up = (sensor._neu @ obs.gcrs_to_itrs)[:, 2, :]
    gcrs = np.concatenate([obs.position_km + 1e5 * up, np.zeros((t.size, 3))], axis=1)
    x = np.asarray(sensor._frame.gcrs_to_synodic(gcrs, t))
    seen = sensor.visible(x, t)
    alt = _astropy_sun_altitude(hours)
    clear = np.abs(alt + 6.0) > 0.05
    assert np.array_equal(seen[clear], alt[clear] <= -6.0)


@pytest.mark.parametrize("table", [{"sun_exclusion": 30.0}, {"limiting_magnitude": "faint"},
                                   {"sun_max_elevation_deg": -120.0}, [1, 2]])
def test_bad_visibility_tables_are_refused(table):
    with pytest.raises(ParameterError, match="visibility"):
        GroundTelescope(visibility=table)
