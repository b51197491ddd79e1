"""A ground telescope measuring azimuth and elevation (and optionally range) of a target.

Registered as sensor ``"ground-telescope"``. The observer sits at a WGS84 geodetic position
(College Station, Texas by default); the synodic -> ECI -> ECEF -> NEU chain is delegated to a
:class:`~cistrack.plugins.sensors.frames.FrameModel` chosen by ``frame_model``.

Measurements: azimuth (rad, North through East, [0, 2pi)), elevation (rad, from the local
horizontal, geodetic up) and, with ``measure_range``, range (LU). Noise: ``sigma_arcsec`` on
both angles; range sigma = ``range_alpha`` x true range.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_choice, check_range, check_sigma_arcsec
from cistrack.errors import MeasurementError
from cistrack.api import hookimpl
from cistrack.astro.sites import MAX_HEIGHT_M, MIN_HEIGHT_M
from cistrack.interfaces import Pass, Sensor
from cistrack.interfaces.sensor import passes_from_mask
from cistrack.model.measurement import MeasurementSet
from cistrack.units import ARCSEC_RAD, LU_KM, parse_utc

from .frames import (FRAME_MODELS, azel_to_unit_neu, geodetic_to_ecef, neu_basis, neu_to_azelr, noisy_measurements)
from .input_checks import checked_states, checked_pass_samples
from .space_frames import IdealSky
from .space_geometry import radec_of, unit_of_radec
from .visibility_rules import sky_rules

__all__ = ["GroundTelescope"]

_BISECTION_STEPS = 48


class GroundTelescope(Sensor):
    """Ground-based optical telescope (az/el, optional IOD-only range).

    Parameters
    ----------
    latitude_deg, longitude_deg : float
        Geodetic WGS84 latitude and longitude of the observer, degrees (East positive).
    height_m : float
        Height above the WGS84 ellipsoid, metres.
    sigma_arcsec : float
        One-sigma noise of azimuth and of elevation, arcseconds.
    measure_range : bool
        Also measure range (the "range" component, LU), for IOD.
    range_alpha : float
        Range sigma as a fraction of the true range.
    elevation_mask_deg : float
        Lowest elevation at which the target is visible, degrees.
    epoch : str
        ISO-8601 UTC time of t = 0 (a scenario injects its own).
    moon_phase_deg : float
        Right ascension of the Earth->Moon direction at the epoch, degrees (equatorial model; a
        CIRS right ascension: true equator of date, counted from the CIO, not J2000).
    frame_model : str
        Name of the synodic-to-Earth-fixed model, one of ``FRAME_MODELS`` ("equatorial", the
        paper's). The real sky is the sensor "real-telescope" (docs/real-sky.md).
    angles : str
        "azel" (the default) or "radec": topocentric right ascension and declination in the frame
        model's ECI axes (geometric, as the angles of "azel"), the angles a space telescope under
        the CR3BP measures, so that simulated ground and space observers make one network
        (docs/space-observers.md; not the ICRF of real astrometry: that is "real-telescope").
        Sigma on RA is sigma_arcsec / cos(Dec).
    visibility : dict or None
        Rules a space telescope also applies, off unless given (docs/space-observers.md): a table of
        sun_exclusion_deg, moon_exclusion_deg, sun_max_elevation_deg, limiting_magnitude,
        diameter_m, albedo, max_range_km. Pass edges are then the samples' (no bisection).
    """

    def _name(self) -> str:
        """The name this class was registered under (a registered subclass's own), in messages."""
        return type(self).registry_name or "ground-telescope"

    def _who(self) -> str:
        return f"sensor '{self._name()}'"

    def __init__(self, latitude_deg: float = 30.618963, longitude_deg: float = -96.339214,
                 height_m: float = 103.8, sigma_arcsec: float = 1.5, measure_range: bool = False,
                 range_alpha: float = 0.05, elevation_mask_deg: float = 10.0,
                 epoch: str = "2026-01-01T00:00:00Z", moon_phase_deg: float = 0.0,
                 frame_model: str = "equatorial", angles: str = "azel",
                 visibility: dict | None = None) -> None:
        self.latitude_deg = check_range(self, "latitude_deg", latitude_deg, -90.0, 90.0)
        self.longitude_deg = check_range(self, "longitude_deg", longitude_deg, -360.0, 360.0)
        self.height_m = check_range(self, "height_m", height_m, MIN_HEIGHT_M, MAX_HEIGHT_M)
        self.sigma_arcsec = check_sigma_arcsec(self, "sigma_arcsec", sigma_arcsec)
        if not isinstance(measure_range, bool):
            self._fail("measure_range", measure_range, "must be true or false")
        self.measure_range = measure_range
        self.range_alpha = check_range(self, "range_alpha", range_alpha, 0.0, 1.0, lo_open=True)
        self.elevation_mask_deg = check_range(self, "elevation_mask_deg", elevation_mask_deg,
                                              -90.0, 90.0, hi_open=True)
        self.moon_phase_deg = check_range(self, "moon_phase_deg", moon_phase_deg, -360.0, 360.0)
        if frame_model == "real":
            self._fail("frame_model", frame_model, "the real sky (DE421 Moon, IERS Earth orientation, "
                       "light time, aberration, refraction, RA/Dec) is the sensor 'real-telescope' "
                       "(docs/real-sky.md); frame models of this sensor: " + ", ".join(FRAME_MODELS))
        self.frame_model = check_choice(self, "frame_model", frame_model, FRAME_MODELS)
        try:
            self._epoch = parse_utc(epoch)
        except (ValueError, TypeError):
            self._fail("epoch", epoch, "must be an ISO-8601 UTC time such as '2026-01-01T00:00:00Z'")
        self.epoch = epoch

        self.angles = check_choice(self, "angles", angles, ("azel", "radec"))
        base = ("azimuth", "elevation") if self.angles == "azel" else ("right_ascension", "declination")
        self.names = base + ("range",) if measure_range else base
        self.angular = (True, False, False) if measure_range else (True, False)
        self._frames = FRAME_MODELS[frame_model](self._epoch, self.moon_phase_deg)
        self._neu = neu_basis(self.latitude_deg, self.longitude_deg)          # (3, 3) ECEF -> NEU
        self._obs_ecef = geodetic_to_ecef(self.latitude_deg, self.longitude_deg,
                                          self.height_m) / LU_KM             # (3,) LU
        self._sigma_rad = self.sigma_arcsec * ARCSEC_RAD
        self._mask_rad = np.radians(self.elevation_mask_deg)
        self.visibility = visibility
        self._rules = sky_rules(self, visibility)
        self._sky = IdealSky(self._epoch, self.moon_phase_deg)

    # -- geometry -------------------------------------------------------------------------------
    def _affine(self, t):
        """A (.., 3, 3), b (.., 3) with NEU = A @ r_syn - b (LU) at t (scalar or (K,)). The last scalar
        time's pair is kept, read-only: a filter step asks for one time many times over."""
        last = getattr(self, "_affine_last", None)
        if last is not None and np.ndim(t) == 0 and last[0] == float(t):
            return last[1], last[2]
        rot, earth = self._frames.synodic_to_ecef(t)
        a = self._neu @ rot
        b = np.einsum("...ij,...j->...i", a, earth) + self._neu @ self._obs_ecef
        if np.ndim(t) == 0:
            a.flags.writeable = b.flags.writeable = False
            self._affine_last = (float(t), a, b)
        return a, b

    def _check_states(self, states) -> np.ndarray:
        return checked_states(self._name(), states)

    def _check_times(self, t, n: int) -> np.ndarray:
        tt = np.asarray(t, dtype=float)
        if tt.ndim == 0:
            return tt
        tt = tt.reshape(-1)
        if tt.shape[0] != n:
            raise MeasurementError(
                f"{self._who()}: t must be a scalar or have one time per row ({n}), "
                f"got shape {np.shape(t)}")
        if tt.size and tt[0] == tt[-1] and np.all(tt == tt[0]):
            return tt[0]                       # one common time: the fast (3, 3) path
        return tt

    def topocentric(self, states: np.ndarray, t) -> np.ndarray:
        """Target positions relative to the observer in the NEU frame, LU.

        states (N, 6) synodic; t scalar or (N,) TU -> (N, 3).
        """
        x = self._check_states(states)
        return self._neu_of_positions(x[:, :3], self._check_times(t, x.shape[0]))

    def _neu_of_positions(self, r: np.ndarray, tt: np.ndarray) -> np.ndarray:
        """NEU (N, 3) of synodic positions r (N, 3) at validated times tt (scalar or (N,))."""
        a, b = self._affine(tt)
        if tt.ndim == 0:
            return r @ a.T - b
        return np.einsum("nij,nj->ni", a, r) - b

    def measure(self, states: np.ndarray, t) -> np.ndarray:
        """Noise-free (azimuth, elevation[, range]) or, with angles = "radec", (RA, Dec[, range]):
        states (N, 6), t scalar or (N,) TU -> (N, m).

        Azimuth in [0, 2pi) rad, elevation in [-pi/2, pi/2] rad, range in LU.
        """
        if self.angles == "radec":
            az, el, rng = self._radec_range(states, t)
        else:
            az, el, rng = neu_to_azelr(self.topocentric(states, t))
        if self.measure_range:
            return np.stack([az, el, rng], axis=1)
        return np.stack([az, el], axis=1)

    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        """One-sigma noise (N, m): angles sigma_arcsec in rad; range range_alpha x true range (LU)."""
        x = self._check_states(states)
        out = np.full((x.shape[0], len(self.names)), self._sigma_rad)
        if self.angles == "radec":
            out[:, 0] /= np.cos(self._radec_range(x, t)[1])
        if self.measure_range:
            out[:, 2] = self.range_alpha * np.linalg.norm(self.topocentric(x, t), axis=1)
        return out

    def _radec_range(self, states, t):
        """Topocentric RA [0, 2pi), Dec (rad) and range (LU) in the frame model's ECI axes, (N,) each."""
        x = self._check_states(states)
        tt = self._check_times(t, x.shape[0])
        rot, _ = self._frames.synodic_to_eci(tt)
        d = x[:, :3] - self.observer_position(tt)
        p = d @ rot.T if tt.ndim == 0 else np.einsum("nij,nj->ni", rot, d)
        ra, dec = radec_of(p)
        return ra, dec, np.linalg.norm(p, axis=1)

    def visible(self, states: np.ndarray, t) -> np.ndarray:
        """Elevation at or above the mask: states (N, 6), t scalar or (N,) -> (N,) bool."""
        neu = self.topocentric(states, t)
        up = np.arctan2(neu[:, 2], np.hypot(neu[:, 0], neu[:, 1])) >= self._mask_rad
        return up & self._sky_allows(states, t) if self._rules.active else up

    def _sky_allows(self, states, t) -> np.ndarray:
        """The ``visibility`` rules, in synodic axes (km): (N,) bool."""
        x, tt = self._check_states(states), self._check_times(t, np.shape(states)[0])
        rot = np.swapaxes(self._sky.rotation(tt), 1, 2)               # inertial -> synodic, (K, 3, 3)
        bodies = {k: np.einsum("kij,kj->ki", rot, v) for k, v in self._sky.bodies_km(tt).items()}
        obs = np.atleast_2d(self.observer_position(tt)) * LU_KM
        up = np.atleast_2d(self._affine(tt)[0][..., 2, :])
        return self._rules.allowed(x[:, :3] * LU_KM - obs, obs, bodies, self._sky.radii_km, up)

    def observer_position(self, t) -> np.ndarray:
        """Observer position in the synodic frame, LU: t scalar -> (3,), (K,) -> (K, 3)."""
        rot, earth = self._frames.synodic_to_ecef(np.asarray(t, dtype=float))
        return earth + np.einsum("...ji,j->...i", rot, self._obs_ecef)

    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        """Unit synodic vectors (N, 3) along (azimuth, elevation) pairs (N, 2) rad at t (scalar or (N,) TU).

        Columns beyond the first two (e.g. range) are ignored. A target at range rho (LU) is at
        ``observer_position(t) + rho * los``.
        """
        ang = np.asarray(angles, dtype=float)
        if ang.ndim != 2 or ang.shape[1] < 2:
            raise MeasurementError(f"{self._who()}: angles must have shape (N, 2), got {ang.shape}")
        if not np.all(np.isfinite(ang[:, :2])):
            raise MeasurementError(f"{self._who()}: angles contain NaN or infinity")
        tt = self._check_times(t, ang.shape[0])
        if self.angles == "radec":
            rot, _ = self._frames.synodic_to_eci(tt)
            u = unit_of_radec(ang[:, 0], ang[:, 1])
            return u @ rot if tt.ndim == 0 else np.einsum("nji,nj->ni", rot, u)
        u = azel_to_unit_neu(ang[:, 0], ang[:, 1])
        a, _ = self._affine(tt)
        if tt.ndim == 0:
            return u @ a
        return np.einsum("nji,nj->ni", a, u)

    def positions_from_measurements(self, values: np.ndarray, t) -> np.ndarray:
        """Synodic positions (N, 3) LU from (azimuth, elevation, range) rows (N, 3) (rad, rad, LU)."""
        v = np.asarray(values, dtype=float)
        if v.ndim != 2 or v.shape[1] < 3:
            raise MeasurementError(
                f"{self._who()}: need (azimuth, elevation, range) rows (N, 3), got {v.shape}")
        tt = self._check_times(t, v.shape[0])
        return self.observer_position(tt) + v[:, 2:3] * self.line_of_sight(v[:, :2], tt)

    # -- passes ---------------------------------------------------------------------------------
    def _elevation_between(self, t0, t1, x0, x1, tau):
        """Elevation (rad) at times tau inside [t0, t1] on a cubic Hermite of the synodic states."""
        h = t1 - t0
        s = ((tau - t0) / h)[:, None]
        s2, s3 = s * s, s * s * s
        p = ((2 * s3 - 3 * s2 + 1) * x0[:, :3] + (s3 - 2 * s2 + s) * h[:, None] * x0[:, 3:6]
             + (-2 * s3 + 3 * s2) * x1[:, :3] + (s3 - s2) * h[:, None] * x1[:, 3:6])
        neu = self._neu_of_positions(p, tau)
        return np.arctan2(neu[:, 2], np.hypot(neu[:, 0], neu[:, 1]))

    def _crossings(self, times, states, k, rising: bool) -> np.ndarray:
        """Mask-crossing times between samples k and k+1 (arrays), found by bisection."""
        if k.size == 0:
            return np.empty(0)
        t0, t1 = times[k], times[k + 1]
        x0, x1 = states[k], states[k + 1]
        lo, hi = t0.copy(), t1.copy()      # invariant: visible side is hi if rising, lo if setting
        for _ in range(_BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            above = self._elevation_between(t0, t1, x0, x1, mid) >= self._mask_rad
            if rising:
                hi = np.where(above, mid, hi)
                lo = np.where(above, lo, mid)
            else:
                lo = np.where(above, mid, lo)
                hi = np.where(above, hi, mid)
        return hi if rising else lo

    def passes(self, times: np.ndarray, states: np.ndarray) -> list[Pass]:
        """Visibility passes of a trajectory sampled at ``times`` (K,) TU with ``states`` (K, 6).

        Contiguous runs of visible samples, with each rise and set refined by bisection of the
        elevation along a cubic Hermite interpolant of the synodic states between the samples.
        A pass already under way at the first sample starts there; one still under way at the
        last sample ends there. Sample densely enough (<= 1 h) not to miss short passes.
        """
        tt, x = checked_pass_samples(self._name(), times, states)
        if tt.size == 0:
            return []
        vis = self.visible(x, tt)
        if self._rules.active:
            return passes_from_mask(tt, vis)
        change = np.flatnonzero(vis[1:] != vis[:-1])           # between change and change + 1
        rise_k = change[vis[change + 1]]
        set_k = change[vis[change]]
        rises = self._crossings(tt, x, rise_k, rising=True)
        sets = self._crossings(tt, x, set_k, rising=False)
        starts = list(rises)
        ends = list(sets)
        if vis[0]:
            starts.insert(0, tt[0])
        if vis[-1]:
            ends.append(tt[-1])
        return [Pass(float(a), float(b)) for a, b in zip(starts, ends)]

    def inertial_frame(self):
        """The frame model's Earth-centred inertial frame (see ``FrameModel.inertial_frame``)."""
        return self._frames.inertial_frame()

    # -- simulation -----------------------------------------------------------------------------
    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        """Noisy measurements of a truth trajectory: states (K, 6) at times (K,) TU.

        Values = h(x) + N(0, sigma^2) per component; azimuth is wrapped into [0, 2pi). The
        caller picks the times (a schedule plans them inside visibility passes).
        """
        x = self._check_states(states)
        tt = np.asarray(times, dtype=float).reshape(-1)
        if tt.shape[0] != x.shape[0]:
            raise MeasurementError(
                f"{self._who()}: {tt.shape[0]} times for {x.shape[0]} states")
        values, s = noisy_measurements(self, x, tt, rng)
        meta = {"sensor": "ground-telescope", "epoch": self.epoch}
        if self.angles == "radec":
            meta["angles"] = "radec"
        return MeasurementSet(tt, values, s, self.names, meta)


@hookimpl
def cistrack_register(registry):
    registry.add("sensor", "ground-telescope", GroundTelescope)
