"""A ground telescope in the real sky: apparent az/el or astrometric RA/Dec of synodic states.

Registered as sensor ``"real-telescope"``. States are nondimensional synodic states in the real
Earth-Moon rotating frame of :class:`cistrack.astro.earth_moon.EarthMoonFrame` (DE421 Moon,
constant LU/TU scaling), the frame the ephemeris dynamics plugin propagates in; the sensor maps
them to GCRS km, km/s with that frame, places the observer with ERFA
(:mod:`cistrack.astro.observer`) and measures with :mod:`cistrack.astro.sky`:

- ``measurement = "azel"``: apparent azimuth (North through East) and elevation; light time,
  annual and diurnal aberration on by default, refraction off by default;
- ``measurement = "radec"``: topocentric astrometric ICRF right ascension and declination as MPC
  and ADES report them (light time on, no aberration, no refraction).

With ``measure_range`` the geometric observer-target distance (LU) is a third component (IOD only).

``line_of_sight`` inverts what does not depend on the target's own motion
(:func:`cistrack.astro.sky.unit_vectors_gcrs`); the miss left, the target's velocity times the light
time, is declared as :attr:`line_of_sight_tolerance_lu`. Every correction applied is named in
``corrections`` and in each simulated set's meta.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_choice, check_range, check_sigma_arcsec
from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.interfaces import Sensor
from cistrack.model.measurement import MeasurementSet
from cistrack.astro.observer import ObserverGeometry, neu_basis
from cistrack.astro.ephemeris import DE421_YEARS, check_de421_epoch
from cistrack.astro.sites import MAX_HEIGHT_M, MIN_HEIGHT_M, Site
from cistrack.astro.sky import (SkyCorrections, apparent_azel, astrometric_radec, standard_pressure_hpa, unit_vectors_gcrs)
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S, VU_KMS, parse_utc

from .frames import noisy_measurements
from .input_checks import checked_states, checked_times, checked_pass_samples
from .space_frames import RealSky
from .visibility_rules import sky_rules

__all__ = ["RealTelescope"]

_MEASUREMENTS = ("azel", "radec")
_NAMES = {"azel": ("azimuth", "elevation"), "radec": ("right_ascension", "declination")}


class RealTelescope(Sensor):
    """Ground telescope with real Earth orientation, light time, aberration and refraction.

    Parameters
    ----------
    latitude_deg, longitude_deg : float
        Geodetic WGS84 latitude and East longitude of the site, degrees.
    height_m : float
        Height of the site above the WGS84 ellipsoid, metres.
    measurement : str
        "azel" (apparent azimuth and elevation) or "radec" (astrometric ICRF right ascension and
        declination, as MPC and ADES report them).
    sigma_arcsec : float
        One-sigma noise of each angle, arcseconds ("radec": on the sky, on RA x cos(Dec) and Dec).
    measure_range : bool
        Also measure the geometric observer-target range (the "range" component, LU), for IOD.
    range_alpha : float
        Range sigma as a fraction of the true range.
    elevation_mask_deg : float
        Lowest geometric elevation at which the target is visible, degrees.
    epoch : str
        ISO-8601 UTC time of t = 0 (a scenario injects its own).
    light_time : bool
        Light-time correction in the barycentric frame (the target is seen where it was).
    annual_aberration : bool or None
        Aberration by the Earth's barycentric velocity (up to 20.5 arcsec); None: on for "azel",
        off for "radec" (which must not have it).
    diurnal_aberration : bool or None
        Aberration by the site's rotation velocity (up to 0.32 arcsec); None: on for "azel",
        off for "radec" (which must not have it).
    refraction : bool
        Atmospheric refraction of the elevation (azel only; needs the site weather below).
    polar_motion : bool
        Apply the IERS polar motion to the site (off: the rotation pole is the ITRS z axis).
    ut1 : bool
        Rotate the Earth by UT1 = UTC + (UT1-UTC) from the bundled IERS table (off: UT1 = UTC).
    pressure_hpa : float
        Site pressure for refraction, hPa; negative: the standard atmosphere at height_m.
    temperature_c : float
        Site air temperature for refraction, degrees Celsius.
    relative_humidity : float
        Site relative humidity for refraction, from 0 to 1.
    wavelength_um : float
        Effective observing wavelength for refraction, micrometres.
    visibility : dict or None
        Sky rules, off unless given, as for "ground-telescope" (docs/space-observers.md); DE421 Sun.
    """

    def _name(self) -> str:
        """The name this class was registered under (a registered subclass's own), in messages."""
        return type(self).registry_name or "real-telescope"

    def _who(self) -> str:
        return f"sensor '{self._name()}'"

    def __init__(self, latitude_deg: float = 30.618963, longitude_deg: float = -96.339214,
                 height_m: float = 103.8, measurement: str = "azel", sigma_arcsec: float = 1.5,
                 measure_range: bool = False, range_alpha: float = 0.05,
                 elevation_mask_deg: float = 10.0, epoch: str = "2026-01-01T00:00:00Z",
                 light_time: bool = True, annual_aberration: bool | None = None,
                 diurnal_aberration: bool | None = None, refraction: bool = False,
                 polar_motion: bool = True, ut1: bool = True, pressure_hpa: float = -1.0,
                 temperature_c: float = 10.0, relative_humidity: float = 0.5,
                 wavelength_um: float = 0.55, visibility: dict | None = None) -> None:
        self.latitude_deg = check_range(self, "latitude_deg", latitude_deg, -90.0, 90.0)
        self.longitude_deg = check_range(self, "longitude_deg", longitude_deg, -360.0, 360.0)
        self.height_m = check_range(self, "height_m", height_m, MIN_HEIGHT_M, MAX_HEIGHT_M)
        self.measurement = check_choice(self, "measurement", measurement, _MEASUREMENTS)
        self.sigma_arcsec = check_sigma_arcsec(self, "sigma_arcsec", sigma_arcsec)
        self.measure_range = self._bool("measure_range", measure_range)
        self.range_alpha = check_range(self, "range_alpha", range_alpha, 0.0, 1.0, lo_open=True)
        self.elevation_mask_deg = check_range(self, "elevation_mask_deg", elevation_mask_deg,
                                              -90.0, 90.0, hi_open=True)
        self._set_epoch(epoch)
        self._set_corrections(light_time, annual_aberration, diurnal_aberration, refraction, polar_motion, ut1)
        self.pressure_hpa = check_range(self, "pressure_hpa", pressure_hpa, -1.0, 2000.0)
        self.temperature_c = check_range(self, "temperature_c", temperature_c, -150.0, 200.0)
        self.relative_humidity = check_range(self, "relative_humidity", relative_humidity, 0.0, 1.0)
        self.wavelength_um = check_range(self, "wavelength_um", wavelength_um, 0.1, 1e6, lo_open=True)
        self._derive()
        self.visibility, self._rules = visibility, sky_rules(self, visibility)
        self._build()

    def _set_epoch(self, epoch: str) -> None:
        """``epoch`` (ISO-8601 UTC, within DE421) as given and parsed (``_epoch``)."""
        try:
            self._epoch = parse_utc(epoch)
        except (ValueError, TypeError):
            self._fail("epoch", epoch, "must be an ISO-8601 UTC time such as '2026-01-01T00:00:00Z'")
        check_de421_epoch(self, epoch, self._epoch.year)  # the Moon and Sun come from DE421
        self.epoch = epoch

    def _set_corrections(self, light_time, annual_aberration, diurnal_aberration, refraction, polar_motion,
                         ut1) -> None:
        """The correction switches; aberration defaults to on for "azel", and "radec" refuses
        aberration and refraction."""
        azel = self.measurement == "azel"
        self.light_time = self._bool("light_time", light_time)
        self.annual_aberration = self._bool("annual_aberration",
                                            azel if annual_aberration is None else annual_aberration)
        self.diurnal_aberration = self._bool("diurnal_aberration",
                                             azel if diurnal_aberration is None else diurnal_aberration)
        self.refraction = self._bool("refraction", refraction)
        self.polar_motion = self._bool("polar_motion", polar_motion)
        self.ut1 = self._bool("ut1", ut1)
        if not azel:
            for name in ("annual_aberration", "diurnal_aberration", "refraction"):
                if getattr(self, name):
                    self._fail(name, True, "must be false for measurement = 'radec': astrometric "
                                           "RA/Dec has no aberration or refraction (use 'azel' "
                                           "for apparent places)")

    def _derive(self) -> None:
        """What the validated settings imply: component names, the SkyCorrections, the
        line-of-sight tolerance (LU), the site and its NEU basis, sigma and mask in rad."""
        base = _NAMES[self.measurement]
        self.names = base + ("range",) if self.measure_range else base
        self.angular = (True, False, False) if self.measure_range else (True, False)
        self.corrections = SkyCorrections(
            light_time=self.light_time, annual_aberration=self.annual_aberration,
            diurnal_aberration=self.diurnal_aberration, refraction=self.refraction,
            polar_motion=self.polar_motion, ut1=self.ut1,
            pressure_hpa=(standard_pressure_hpa(self.height_m) if self.pressure_hpa < 0 else self.pressure_hpa),
            temperature_c=self.temperature_c, relative_humidity=self.relative_humidity,
            wavelength_um=self.wavelength_um)
        # observer + range * los misses the target by |v| tau (module docstring): allow 4 km/s.
        self.line_of_sight_tolerance_lu = (4.0 * 1.5 / LU_KM) if self.light_time else 1e-9
        self._site = Site(float(self.latitude_deg), float(self.longitude_deg), float(self.height_m))
        self._neu = neu_basis(self._site)
        self._sigma_rad = self.sigma_arcsec * ARCSEC_RAD
        self._mask_rad = np.radians(self.elevation_mask_deg)

    def _bool(self, name: str, value) -> bool:
        if not isinstance(value, (bool, np.bool_)):
            self._fail(name, value, "must be true or false")
        return bool(value)

    def _build(self) -> None:
        from cistrack.astro.earth_moon import EarthMoonFrame

        self._frame = EarthMoonFrame.from_utc(self._epoch)
        self._observer = ObserverGeometry(self._site, self._epoch, polar_motion=self.polar_motion, ut1=self.ut1)

    def inertial_frame(self):
        """GCRS (CCSDS ``GCRF``): the real Earth-Moon frame's synodic -> GCRS map (DE421), used
        to export estimates (``cistrack export``)."""
        from cistrack.astro.inertial_frame import InertialFrame
        return InertialFrame(name="GCRF", ccsds=True, from_synodic=self._frame.synodic_to_gcrs,
                             description="GCRS: Earth-centred, ICRF-aligned axes; from the real "
                                         "Earth-Moon rotating frame (DE421)", years=DE421_YEARS)

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_frame", None)
        state.pop("_observer", None)
        return state

    def __setstate__(self, state) -> None:
        self.__dict__.update(state)
        self._build()

    # -- validation -----------------------------------------------------------------------------
    def _check_states(self, states) -> np.ndarray:
        return checked_states(self._name(), states)

    def _check_times(self, t, n: int) -> np.ndarray:
        return checked_times(self._name(), t, n)

    # -- geometry -------------------------------------------------------------------------------
    def _gcrs(self, x: np.ndarray, tt: np.ndarray):
        """GCRS position (N, 3) km, velocity (N, 3) km/s and observer state at times tt.

        The frame (DE421) and the observer (ERFA) are evaluated once per distinct time; the
        transform is that of ``EarthMoonFrame.synodic_to_gcrs`` (constant LU/VU scaling).
        """
        if tt.ndim == 0:
            uniq, inv = tt.reshape(1), np.zeros(x.shape[0], dtype=int)
        else:
            uniq, inv = np.unique(tt, return_inverse=True)
        ax = self._frame.axes(uniq)
        if uniq.size == 1:                                               # one time: (3, 3) products
            rot = ax.rotation[0]
            rho = (x[:, :3] * LU_KM) @ rot.T
            rhod = (x[:, 3:] * VU_KMS) @ rot.T
            r = ax.origin[0] + rho
            v = ax.origin_velocity[0] + rhod + np.cross(ax.omega[0], rho)
        else:
            rot = ax.rotation[inv]                                       # (N, 3, 3)
            rho = np.einsum("nij,nj->ni", rot, x[:, :3] * LU_KM)
            rhod = np.einsum("nij,nj->ni", rot, x[:, 3:] * VU_KMS)
            r = ax.origin[inv] + rho
            v = ax.origin_velocity[inv] + rhod + np.cross(ax.omega[inv], rho)
        obs = self._observer.state(tt * TU_S)
        return r, v, obs

    def measure(self, states: np.ndarray, t) -> np.ndarray:
        """Noise-free angles (rad) [and range, LU]: states (N, 6) synodic, t scalar or (N,) TU -> (N, m).

        azel: azimuth [0, 2pi), elevation; radec: right ascension [0, 2pi), declination.
        """
        x = self._check_states(states)
        tt = self._check_times(t, x.shape[0])
        r, v, obs = self._gcrs(x, tt)
        if self.measurement == "azel":
            a, b, _ = apparent_azel(r, v, obs, self._neu, self.corrections, self.height_m)
        else:
            a, b, _ = astrometric_radec(r, v, obs, self.corrections.light_time)
        if self.measure_range:
            rng = np.linalg.norm(r - obs.position_km, axis=1) / LU_KM
            return np.stack([a, b, rng], axis=1)
        return np.stack([a, b], axis=1)

    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        """One-sigma noise (N, m): sigma_arcsec per angle, rad ("radec": on the sky, / cos(Dec) on RA); range_alpha x range."""
        x, tt = self._check_states(states), self._check_times(t, np.shape(states)[0])
        out = np.full((x.shape[0], len(self.names)), self._sigma_rad)
        if self.measurement == "radec":
            out[:, 0] /= np.cos(self.measure(x, tt)[:, 1])
        if self.measure_range:
            out[:, 2] = self.range_alpha * np.linalg.norm(x[:, :3] - self.observer_position(tt), axis=1)
        return out

    def _geometric_elevation(self, x: np.ndarray, tt: np.ndarray) -> np.ndarray:
        r, _, obs = self._gcrs(x, tt)
        m = self._neu @ obs.gcrs_to_itrs                                 # (K, 3, 3)
        d = r - obs.position_km
        neu = np.einsum("kij,kj->ki", m, d) if m.shape[0] == d.shape[0] else d @ m[0].T
        el = np.arctan2(neu[:, 2], np.hypot(neu[:, 0], neu[:, 1]))
        if not self._rules.active:
            return el
        sky = RealSky(self._frame)       # the visibility rules: a target they refuse is "below"
        ok = self._rules.allowed(d, obs.position_km, sky.bodies_km(tt), sky.radii_km, m[:, 2, :])
        return np.where(ok, el, -np.pi / 2)

    def visible(self, states: np.ndarray, t) -> np.ndarray:
        """Geometric elevation at or above the mask (and the ``visibility`` rules): (N, 6), t -> (N,) bool."""
        x = self._check_states(states)
        return self._geometric_elevation(x, self._check_times(t, x.shape[0])) >= self._mask_rad

    def observer_position(self, t) -> np.ndarray:
        """Observer position in the synodic frame, LU: t scalar -> (3,), (K,) -> (K, 3)."""
        tt = np.asarray(t, dtype=float)
        obs = self._observer.state(tt * TU_S)
        pv = np.concatenate([obs.position_km, obs.velocity_kms], axis=1)
        syn = np.asarray(self._frame.gcrs_to_synodic(pv, tt.reshape(-1) if tt.ndim else tt),
                         dtype=float).reshape(-1, 6)[:, :3]
        return syn[0] if tt.ndim == 0 else syn

    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        """Unit synodic vectors (N, 3) towards the target for measured angle pairs (N, 2) rad at t.

        Undoes refraction, aberration and the Earth's motion during the light time (see the
        module docstring); extra columns (range) are ignored.
        """
        ang = np.asarray(angles, dtype=float)
        if ang.ndim != 2 or ang.shape[1] < 2:
            raise MeasurementError(f"{self._who()}: angles must have shape (N, 2), got {ang.shape}")
        if not np.all(np.isfinite(ang[:, :2])):
            raise MeasurementError(f"{self._who()}: angles contain NaN or infinity")
        tt = self._check_times(t, ang.shape[0])
        obs = self._observer.state(tt * TU_S)
        u = unit_vectors_gcrs(ang[:, 0], ang[:, 1], obs, self._neu, self.corrections,
                              azel=self.measurement == "azel", height_m=self.height_m)
        if tt.ndim == 0:
            los = u @ self._frame.axes(float(tt)).rotation[0]
        else:
            uniq, inv = np.unique(tt, return_inverse=True)
            rot = self._frame.axes(uniq).rotation[inv]                          # (N, 3, 3)
            los = np.einsum("kji,kj->ki", rot, u)
        return los / np.linalg.norm(los, axis=1)[:, None]

    # -- passes and simulation ------------------------------------------------------------------
    def passes(self, times: np.ndarray, states: np.ndarray):
        """Visibility passes: contiguous runs of visible samples (sample at <= 1 h spacing)."""
        tt, x = checked_pass_samples(self._name(), times, states)
        return super().passes(tt, x)

    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        """Noisy measurements of a truth trajectory: states (K, 6) synodic at times (K,) TU."""
        x = self._check_states(states)
        tt = np.asarray(times, dtype=float).reshape(-1)
        if tt.shape[0] != x.shape[0]:
            raise MeasurementError(f"{self._who()}: {tt.shape[0]} times for {x.shape[0]} states")
        values, s = noisy_measurements(self, x, tt, rng)
        meta = {"sensor": "real-telescope", "epoch": self.epoch, "measurement": self.measurement,
                "frame": "real Earth-Moon rotating (DE421)", "corrections": self.corrections.applied(),
                "site": {"latitude_deg": self.latitude_deg, "longitude_deg": self.longitude_deg,
                         "height_m": self.height_m}}
        return MeasurementSet(tt, values, s, self.names, meta)


@hookimpl
def cistrack_register(registry):
    registry.add("sensor", "real-telescope", RealTelescope)
