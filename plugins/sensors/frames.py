"""Reference frames between the synodic CR3BP frame and a ground observer's sky.

Chain (positions; every length here is LU unless a name says otherwise)::

    synodic (barycentric, rotating)
      -> Earth-centred inertial (ECI): subtract the Earth's synodic position, rotate by the
         synodic angle theta(t)
      -> Earth-centred Earth-fixed (ECEF): rotate by the Earth rotation angle ERA(UTC)
      -> topocentric NEU (North, East, Up; geodetic WGS84 up) at the observer
      -> azimuth (from North through East, [0, 2pi)), elevation (from the horizontal), range.

A :class:`FrameModel` supplies the first two steps as one rotation matrix per time and the
Earth's synodic position: ``r_ecef = R(t) @ (r_syn - earth_syn(t))``. The default,
:class:`EquatorialFrameModel`, is the paper's simplified geometry (Earth–Moon plane in the
equator, synodic frame turning at 1 rad/TU about z, Earth at (-mu, 0, 0)); a higher-fidelity
model (inclined lunar orbit, ephemerides) is another subclass registered in
:data:`FRAME_MODELS`.

Because ECI -> ECEF is the Earth rotation angle alone, this "ECI" is the CIRS (true equator of
date, origin at the CIO), not J2000/ICRF nor the equinox of date: ``moon_phase_deg`` is a CIRS
right ascension. The real geometry (DE421 Moon, precession-nutation, polar motion, UT1, light
time, aberration, refraction) is the separate sensor ``real-telescope``; see docs/real-sky.md.

Time ``t`` is TU since the epoch (UTC). UT1 is taken equal to UTC (|UT1-UTC| < 0.9 s, i.e.
< 14 arcsec of Earth rotation; the sensor noise is 1.5 arcsec, so supply a better model if you
fit real data to that level).
"""
from __future__ import annotations

from datetime import datetime, timezone

import numpy as np

from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.astro.rotating_frame import rot_z, synodic_to_eci
from cistrack.units import DAY_S, LU_KM, TU_S

__all__ = [
    "MU", "WGS84_A_M", "WGS84_F", "J2000_UTC",
    "earth_rotation_angle", "days_since_j2000", "rot_z",
    "geodetic_to_ecef", "neu_basis",
    "wrap_azimuth", "neu_to_azelr", "azelr_to_neu", "azel_to_unit_neu",
    "FrameModel", "EquatorialFrameModel", "FRAME_MODELS",
]

MU: float = MU_EARTH_MOON
"""Earth–Moon mass ratio (:mod:`cistrack.astro.primaries`)."""
WGS84_A_M: float = 6_378_137.0
"""WGS84 equatorial radius, m."""
WGS84_F: float = 1.0 / 298.257223563
"""WGS84 flattening."""
J2000_UTC = datetime(2000, 1, 1, 12, 0, 0, tzinfo=timezone.utc)
"""The J2000 epoch (JD 2451545.0), taken as UT1 = UTC."""

_TWO_PI = 2.0 * np.pi


def days_since_j2000(epoch: datetime) -> tuple[float, float]:
    """Days from J2000 to ``epoch`` split as (whole days, fraction of a day in [0, 1))."""
    delta = epoch.astimezone(timezone.utc) - J2000_UTC
    whole = float(delta.days)
    frac = (delta.seconds + delta.microseconds * 1e-6) / DAY_S
    return whole, frac


def earth_rotation_angle(epoch: datetime, t) -> np.ndarray:
    """Earth rotation angle (IERS 2003), rad in [0, 2pi), at ``t`` TU after ``epoch`` (UT1 = UTC).

    ERA = 2pi (0.7790572732640 + 1.00273781191135448 Du), Du = JD(UT1) - 2451545.0. The
    whole-day part of Du is split off so that the result keeps ~1e-12 rad precision.
    t : scalar or (K,) TU  ->  scalar or (K,) rad.
    """
    whole, frac = days_since_j2000(epoch)
    dfrac = frac + np.asarray(t, dtype=float) * (TU_S / DAY_S)   # fraction of days past `whole`
    turns = 0.7790572732640 + 0.00273781191135448 * (whole + dfrac) + np.mod(dfrac, 1.0)
    return _TWO_PI * np.mod(turns, 1.0)


def geodetic_to_ecef(latitude_deg: float, longitude_deg: float, height_m: float) -> np.ndarray:
    """WGS84 geodetic coordinates (deg, deg, m) -> ECEF position (3,) in km."""
    lat = np.radians(latitude_deg)
    lon = np.radians(longitude_deg)
    e2 = WGS84_F * (2.0 - WGS84_F)
    n = WGS84_A_M / np.sqrt(1.0 - e2 * np.sin(lat) ** 2)
    x = (n + height_m) * np.cos(lat) * np.cos(lon)
    y = (n + height_m) * np.cos(lat) * np.sin(lon)
    z = (n * (1.0 - e2) + height_m) * np.sin(lat)
    return np.array([x, y, z]) / 1000.0


def neu_basis(latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """Rows North, East, Up (geodetic) of the topocentric frame, in ECEF: (3, 3).

    ``r_neu = neu_basis(...) @ r_ecef`` for a vector from the observer.
    """
    lat = np.radians(latitude_deg)
    lon = np.radians(longitude_deg)
    sl, cl = np.sin(lat), np.cos(lat)
    so, co = np.sin(lon), np.cos(lon)
    return np.array([
        [-sl * co, -sl * so, cl],   # North
        [-so, co, 0.0],             # East
        [cl * co, cl * so, sl],     # Up
    ])


def wrap_azimuth(az) -> np.ndarray:
    """Angles (rad, any shape) wrapped into [0, 2pi) (never 2pi itself)."""
    a = np.mod(np.asarray(az, dtype=float), _TWO_PI)
    return np.where(a >= _TWO_PI, 0.0, a)


def noisy_measurements(sensor, states: np.ndarray, times: np.ndarray,
                       rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``sensor``'s measurements of states (K, 6) at times (K,) TU with Gaussian noise of its
    sigmas, the first angle (azimuth or right ascension) wrapped into [0, 2pi): (values, sigmas),
    each (K, m)."""
    z = sensor.measure(states, times)
    s = sensor.sigmas(states, times)
    values = z + rng.standard_normal(z.shape) * s
    values[:, 0] = wrap_azimuth(values[:, 0])
    return values, s


def neu_to_azelr(neu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Topocentric NEU vectors (..., 3) -> azimuth [0, 2pi), elevation [-pi/2, pi/2], range.

    Azimuth runs from North through East; range is in the unit of ``neu``.
    """
    n, e, u = neu[..., 0], neu[..., 1], neu[..., 2]
    horiz = np.hypot(n, e)
    az = np.arctan2(e, n)
    az = np.where(az < 0.0, az + _TWO_PI, az)
    az = np.where(az >= _TWO_PI, 0.0, az)         # -1e-17 + 2pi rounds to 2pi
    el = np.arctan2(u, horiz)
    rng = np.sqrt(horiz * horiz + u * u)
    return az, el, rng


def azel_to_unit_neu(az, el) -> np.ndarray:
    """Azimuth, elevation (rad, same shape S) -> unit NEU vectors (S + (3,))."""
    az = np.asarray(az, dtype=float)
    el = np.asarray(el, dtype=float)
    ce = np.cos(el)
    return np.stack([ce * np.cos(az), ce * np.sin(az), np.sin(el)], axis=-1)


def azelr_to_neu(az, el, rng) -> np.ndarray:
    """Azimuth, elevation (rad) and range (any length unit), shape S -> NEU vectors (S + (3,))."""
    return azel_to_unit_neu(az, el) * np.asarray(rng, dtype=float)[..., None]


class FrameModel:
    """How the synodic frame sits in the Earth-fixed frame at each time.

    Subclasses implement :meth:`synodic_to_ecef`. Instances must be picklable and cheap to
    build; a sensor builds one from its ``frame_model`` parameter.
    """

    name: str = ""

    def __init__(self, epoch: datetime, moon_phase_deg: float = 0.0) -> None:
        self.epoch = epoch
        self.moon_phase_deg = float(moon_phase_deg)

    def synodic_to_ecef(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Rotation and Earth position at t (scalar -> (3, 3), (3,); (K,) -> (K, 3, 3), (K, 3)).

        ``r_ecef = R @ (r_syn - earth_syn)`` (LU in, LU out).
        """
        raise NotImplementedError

    def synodic_to_eci(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Rotation and Earth position such that ``r_eci = R @ (r_syn - earth_syn)``."""
        raise NotImplementedError

    def inertial_frame(self):
        """The model's Earth-centred inertial frame for exports (None: not defined)."""
        return None


class EquatorialFrameModel(FrameModel):
    """The paper's simplified geometry.

    The Earth–Moon plane is the equator; the synodic x axis (Earth -> Moon) has right
    ascension ``moon_phase_deg + t`` (rad, t in TU) in the ECI frame, i.e. the synodic frame
    turns counter-clockwise at 1 rad/TU about the ECI z axis; the Earth is at (-mu, 0, 0).
    ECEF follows from ECI by the Earth rotation angle.
    """

    name = "equatorial"

    def _earth(self, t: np.ndarray) -> np.ndarray:
        out = np.zeros(t.shape + (3,))
        out[..., 0] = -MU
        return out

    def synodic_angle(self, t) -> np.ndarray:
        """Right ascension of the synodic x axis, rad: t scalar or (K,) TU."""
        return np.radians(self.moon_phase_deg) + np.asarray(t, dtype=float)

    def synodic_to_eci(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        return rot_z(self.synodic_angle(t)), self._earth(t)

    def synodic_to_ecef(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        angle = self.synodic_angle(t) - earth_rotation_angle(self.epoch, t)
        return rot_z(angle), self._earth(t)

    def states_to_eci_km(self, states: np.ndarray, t) -> np.ndarray:
        """Synodic states (N, 6) at t ((N,) TU) -> this model's ECI (N, 6) km, km/s: the core
        synodic -> ECI map (frame turning at 1 rad/TU, Earth at (-mu, 0, 0)) followed by the
        rotation by ``moon_phase_deg``."""
        x = np.atleast_2d(np.asarray(states, dtype=float))
        eci = synodic_to_eci(x, np.broadcast_to(np.asarray(t, dtype=float), (x.shape[0],)), MU_EARTH_MOON)
        rot = rot_z(np.radians(self.moon_phase_deg))
        return np.concatenate([eci[:, :3] @ rot.T * LU_KM, eci[:, 3:] @ rot.T * (LU_KM / TU_S)], axis=1)

    def inertial_frame(self):
        from cistrack.astro.inertial_frame import InertialFrame
        return InertialFrame(
            name=IDEAL_FRAME_NAME, ccsds=False, from_synodic=self.states_to_eci_km,
            description="cistrack's idealised equatorial model (the paper's CR3BP geometry): "
                        "Earth-Moon plane in the equator, x at the celestial intermediate origin "
                        "(UT1 = UTC); axes like CIRS but not CIRS, and not a CCSDS-registered frame")


IDEAL_FRAME_NAME = "CISTRACK-IDEAL-EQUATORIAL"
"""REF_FRAME of estimates exported from the idealised model: a name no reader can take for a real
IERS or CCSDS frame (CIRS was written before: the axes are CIRS-like, the geometry is not)."""

FRAME_MODELS: dict[str, type[FrameModel]] = {"equatorial": EquatorialFrameModel}
"""Frame models selectable by a sensor's ``frame_model`` parameter (name -> class)."""
