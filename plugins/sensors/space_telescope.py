"""A telescope in space: right ascension and declination of a target from an observer that moves
on its own orbit under the run's dynamics (docs/space-observers.md).

Registered as sensor ``"space-telescope"``. The observer's trajectory
(:class:`~cistrack.plugins.sensors.observer_orbit.ObserverOrbit`) starts from a catalog orbit at a
phase (``orbit``, ``phase``) or from a state and its epoch (``state_km``, ``state_epoch``) and is
propagated by the run's dynamics (a scenario hands its ``[truth.dynamics]``, else its
``[dynamics]``, to the sensor's ``dynamics`` parameter). The sky
(:mod:`~cistrack.plugins.sensors.space_frames`) follows the dynamics: the idealised equatorial
frame under the CR3BP, GCRS (DE421) under the ephemeris model.

Measurements: right ascension [0, 2pi) and declination (rad) of the astrometric direction
``p = r_t(t - tau) - r_o(t)`` (light time tau = |p| / c solved in the frame's inertial,
barycentric sense, the target's path over tau to second order; off with ``light_time = false``),
optionally the geometric range (LU) and range rate (VU). Visibility: the exclusion cones about the
Sun, Earth and Moon limbs and the detection model of
:mod:`~cistrack.plugins.sensors.visibility_rules`.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import MeasurementError
from cistrack.interfaces import Dynamics, Sensor
from cistrack.interfaces.sensor import passes_from_mask
from cistrack.interfaces.component import check_positive, check_range, check_sigma_arcsec
from cistrack.model.measurement import MeasurementSet
from cistrack.api import hookimpl
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S, VU_KMS, parse_utc

from .frames import noisy_measurements
from .input_checks import checked_states, checked_times, checked_pass_samples
from .observer_orbit import ObserverOrbit, observer_start
from .space_frames import RealSky, sky_for
from .space_geometry import astrometric_direction, radec_of, unit_of_radec
from .visibility_rules import ExclusionRules, Photometry, SkyRules

__all__ = ["SpaceTelescope"]


MIN_SEPARATION_KM = 1.0
"""The closest the target may come to a space telescope (km): nearer, it is the observer itself."""


class SpaceTelescope(Sensor):
    """Optical telescope on an orbit in cislunar space (RA/Dec, optional range and range rate).

    Parameters
    ----------
    orbit : str or None
        Registered orbit the observer flies (``cistrack plugins`` lists them under "orbit");
        None: "dro-2-1" unless ``state_km`` is given. Exclusive with ``state_km``.
    phase : float
        Fraction of the orbit's period the observer is along it at t = 0, in [0, 1).
    state_km : list of 6 floats or None
        Observer state [x, y, z km, vx, vy, vz km/s], synodic barycentric (instead of ``orbit``;
        the two are exclusive).
    state_epoch : str
        ISO-8601 UTC time of ``state_km``, at or before the scenario epoch and at most 366 days
        before it ("" = the epoch).
    dynamics : Dynamics, name or None
        Model that moves the observer; a scenario hands its own. None: the Earth-Moon CR3BP.
    epoch : str
        ISO-8601 UTC time of t = 0 (a scenario injects its own).
    sigma_arcsec : float
        One-sigma noise on the sky, arcseconds (on RA x cos(Dec) and on Dec).
    measure_range, measure_range_rate : bool
        Also measure the geometric range (LU) / range rate (VU).
    range_alpha : float
        Range sigma as a fraction of the true range.
    range_rate_sigma_kms : float
        One-sigma range-rate noise, km/s.
    light_time : bool
        Light-time correction (the target is seen where it was).
    sun_exclusion_deg, earth_exclusion_deg, moon_exclusion_deg : float
        Exclusion angles from each body's limb, degrees (negative: no exclusion).
    diameter_m, albedo : float
        Size and albedo of the target (a diffuse sphere) for the detection model.
    limiting_magnitude : float
        Faintest visual magnitude detected (<= 0: every target is bright enough).
    max_range_km : float
        Largest range at which the target is sought, km (<= 0: no limit).
    moon_phase_deg : float
        CR3BP only: right ascension of the Earth->Moon direction at the epoch, degrees.
    revisit_hours, window_hours, first_window_hours : float
        Tasking: the sensor turns to the target for ``window_hours`` every ``revisit_hours``, the
        first window opening at ``first_window_hours``; passes are the visible parts of those
        windows (what the schedules plan in). revisit_hours = 0: passes are the whole visibility.
    """

    def _name(self) -> str:
        """The name this class was registered under (a registered subclass's own), in messages."""
        return type(self).registry_name or "space-telescope"

    def _who(self) -> str:
        return f"sensor '{self._name()}'"

    def __init__(self, orbit: str | None = None, phase: float = 0.0, state_km: list[float] | None = None,
                 state_epoch: str = "", dynamics: Dynamics | str | None = None,
                 epoch: str = "2026-01-01T00:00:00Z", sigma_arcsec: float = 1.0,
                 measure_range: bool = False, measure_range_rate: bool = False, range_alpha: float = 0.05,
                 range_rate_sigma_kms: float = 0.001, light_time: bool = True,
                 sun_exclusion_deg: float = 30.0, earth_exclusion_deg: float = 10.0,
                 moon_exclusion_deg: float = 5.0, diameter_m: float = 2.0, albedo: float = 0.2,
                 limiting_magnitude: float = 19.0, max_range_km: float = 0.0,
                 moon_phase_deg: float = 0.0, revisit_hours: float = 0.0, window_hours: float = 8.0,
                 first_window_hours: float = 1.0) -> None:
        self.phase = check_range(self, "phase", phase, 0.0, 1.0, hi_open=True)
        self.sigma_arcsec = check_sigma_arcsec(self, "sigma_arcsec", sigma_arcsec)
        self._set_measured(measure_range, measure_range_rate, light_time, range_alpha, range_rate_sigma_kms)
        for name, value in (("sun_exclusion_deg", sun_exclusion_deg), ("earth_exclusion_deg", earth_exclusion_deg),
                            ("moon_exclusion_deg", moon_exclusion_deg)):
            setattr(self, name, check_range(self, name, value, -1.0, 180.0))
        self._set_photometry(diameter_m, albedo, limiting_magnitude, max_range_km)
        self.moon_phase_deg = check_range(self, "moon_phase_deg", moon_phase_deg, -360.0, 360.0)
        self._set_tasking(revisit_hours, window_hours, first_window_hours)
        self._set_epoch(epoch)
        self.dynamics = self._checked_dynamics(dynamics)
        self.orbit, self.state_km, self.state_epoch = orbit, state_km, state_epoch
        x0, t0 = self._start()
        self._orbit = ObserverOrbit(self.dynamics, x0, t0, self._name())
        self._sky = sky_for(self.dynamics, self._epoch, self.moon_phase_deg)
        self._set_names()

    def _set_measured(self, measure_range, measure_range_rate, light_time, range_alpha,
                      range_rate_sigma_kms) -> None:
        """The measured components' switches and the range (fraction) and range-rate (km/s) noise."""
        for name, value in (("measure_range", measure_range), ("measure_range_rate", measure_range_rate),
                            ("light_time", light_time)):
            if not isinstance(value, (bool, np.bool_)):
                self._fail(name, value, "must be true or false")
        self.measure_range, self.measure_range_rate = bool(measure_range), bool(measure_range_rate)
        self.light_time = bool(light_time)
        self.range_alpha = check_range(self, "range_alpha", range_alpha, 0.0, 1.0, lo_open=True)
        self.range_rate_sigma_kms = check_positive(self, "range_rate_sigma_kms", range_rate_sigma_kms)

    def _set_photometry(self, diameter_m, albedo, limiting_magnitude, max_range_km) -> None:
        """The detection model's settings, and the sky rules with the exclusion angles set before."""
        self.diameter_m = check_positive(self, "diameter_m", diameter_m)
        self.albedo = check_range(self, "albedo", albedo, 0.0, 1.0, lo_open=True)
        self.limiting_magnitude = check_range(self, "limiting_magnitude", limiting_magnitude, -30.0, 40.0)
        self.max_range_km = check_range(self, "max_range_km", max_range_km, -1.0, 1e9)
        self._rules = SkyRules(ExclusionRules(self.sun_exclusion_deg, self.earth_exclusion_deg, self.moon_exclusion_deg),
                               Photometry(self.diameter_m, self.albedo, self.limiting_magnitude, self.max_range_km))

    def _set_tasking(self, revisit_hours, window_hours, first_window_hours) -> None:
        """Revisit period, window length and first window opening, hours."""
        self.revisit_hours = check_range(self, "revisit_hours", revisit_hours, 0.0, 1e5)
        self.window_hours = check_positive(self, "window_hours", window_hours)
        self.first_window_hours = check_range(self, "first_window_hours", first_window_hours, 0.0, 1e5)
        if 0 < self.revisit_hours < self.window_hours:
            self._fail("window_hours", window_hours, f"must not exceed revisit_hours = {self.revisit_hours:g}")

    def _set_epoch(self, epoch: str) -> None:
        """``epoch`` (ISO-8601 UTC) as given and parsed (``_epoch``)."""
        try:
            self._epoch = parse_utc(epoch)
        except (ValueError, TypeError):
            self._fail("epoch", epoch, "must be an ISO-8601 UTC time such as '2026-01-01T00:00:00Z'")
        self.epoch = epoch

    def _checked_dynamics(self, dynamics) -> Dynamics:
        """The dynamics that moves the observer (None: the registered Earth-Moon CR3BP); its own
        epoch, if it has one, must be the sensor's."""
        if dynamics is None:                    # outside a scenario: the registered Earth-Moon CR3BP
            from cistrack.api import default_registry
            dynamics = default_registry().create("dynamics", "cr3bp")
        if not isinstance(dynamics, Dynamics):
            self._fail("dynamics", dynamics, "must be a dynamics model (a scenario hands the run's own)")
        own = getattr(dynamics, "epoch", None)
        if isinstance(own, str) and parse_utc(own) != self._epoch:
            self._fail("dynamics", dynamics, f"its epoch {own} must be the sensor's epoch {self.epoch}")
        return dynamics

    def _set_names(self) -> None:
        """Component names and angular flags, the line-of-sight tolerance (LU) and sigma (rad)."""
        names = ["right_ascension", "declination"]
        names += ["range"] if self.measure_range else []
        names += ["range_rate"] if self.measure_range_rate else []
        self.names = tuple(names)
        self.angular = (True,) + (False,) * (len(names) - 1)
        drift = 31.0 if isinstance(self._sky, RealSky) else 0.0   # km/s: the Earth's own motion (BCRS)
        self.line_of_sight_tolerance_lu = ((4.0 + drift) * 1.5 / LU_KM) if self.light_time else 1e-9
        self._sigma_rad = self.sigma_arcsec * ARCSEC_RAD

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_sky", None)                       # DE421 readers are rebuilt, not shipped
        return state

    def __setstate__(self, state) -> None:
        self.__dict__.update(state)
        self._sky = sky_for(self.dynamics, self._epoch, self.moon_phase_deg)

    def _start(self) -> tuple[np.ndarray, float]:
        x0, t0, self.orbit = observer_start(self.orbit, self.phase, self.state_km, self.state_epoch,
                                            self._epoch, self._fail)
        return x0, t0

    # -- validation -----------------------------------------------------------------------------
    def _check_states(self, states) -> np.ndarray:
        return checked_states(self._name(), states)

    def _check_times(self, t, n: int) -> np.ndarray:
        return checked_times(self._name(), t, n)

    # -- geometry -------------------------------------------------------------------------------
    def observer_states(self, t) -> np.ndarray:
        """Observer synodic states: t scalar -> (6,), (K,) -> (K, 6) (LU, VU)."""
        tt = np.asarray(t, dtype=float)
        s = self._orbit.states(tt)
        return s[0] if tt.ndim == 0 else s

    def observer_position(self, t) -> np.ndarray:
        """Observer position in the synodic frame, LU: t scalar -> (3,), (K,) -> (K, 3)."""
        return self.observer_states(t)[..., :3]

    def _inertial(self, x: np.ndarray, tt: np.ndarray):
        """Target and observer inertial states (N, 6) and (N or 1, 6), km, km/s."""
        obs = self._orbit.states(tt)
        return self._sky.states_km(x, tt), self._sky.states_km(obs, tt)

    def measure(self, states: np.ndarray, t) -> np.ndarray:
        """Noise-free (RA, Dec[, range][, range_rate]): states (N, 6), t scalar or (N,) TU -> (N, m).

        RA in [0, 2pi) rad, Dec in [-pi/2, pi/2] rad, range LU, range rate VU.
        """
        x = self._check_states(states)
        tt = self._check_times(t, x.shape[0])
        tgt, obs = self._inertial(x, tt)
        if self.light_time:
            p = astrometric_direction(tgt, obs, self._sky.gravity_kms2(x, tt), self._sky.drift_kms(tt))
        else:
            p = tgt[:, :3] - obs[:, :3]
        ra, dec = radec_of(p)
        cols = [ra, dec]
        d = tgt[:, :3] - obs[:, :3]
        rng = np.linalg.norm(d, axis=1)
        if self.measure_range:
            cols.append(rng / LU_KM)
        if self.measure_range_rate:
            cols.append(np.einsum("ni,ni->n", d, tgt[:, 3:] - obs[:, 3:]) / rng / VU_KMS)
        return np.stack(cols, axis=1)

    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        """One-sigma noise (N, m): sigma_arcsec / cos(Dec) on RA and sigma_arcsec on Dec (rad);
        range_alpha x range (LU); range_rate_sigma_kms (VU)."""
        x = self._check_states(states)
        tt = self._check_times(t, x.shape[0])
        out = np.full((x.shape[0], len(self.names)), self._sigma_rad)
        z = self.measure(x, tt)
        out[:, 0] /= np.cos(z[:, 1])
        if self.measure_range:
            out[:, self.names.index("range")] = self.range_alpha * z[:, self.names.index("range")]
        if self.measure_range_rate:
            out[:, self.names.index("range_rate")] = self.range_rate_sigma_kms / VU_KMS
        return out

    def visible(self, states: np.ndarray, t) -> np.ndarray:
        """Outside every exclusion cone and detectable: states (N, 6), t scalar or (N,) -> (N,) bool."""
        x = self._check_states(states)
        tt = self._check_times(t, x.shape[0])
        return self._allowed(*self._inertial(x, tt), tt)

    def _allowed(self, tgt: np.ndarray, obs: np.ndarray, tt: np.ndarray) -> np.ndarray:
        """:meth:`visible` of the inertial target and observer states (N, 6) km at ``tt``."""
        return self._rules.allowed(tgt[:, :3] - obs[:, :3], obs[:, :3], self._sky.bodies_km(tt), self._sky.radii_km)

    def exclusion_cones(self, t: float) -> dict[str, tuple[np.ndarray, float]]:
        """The active exclusion cones at t (TU): body -> (unit synodic axis (3,) from the observer to
        the body's centre, half-angle rad = apparent radius + exclusion angle). For viewers."""
        rot = self._sky.rotation(float(t))[0]
        obs = self._sky.states_km(self._orbit.states(float(t)), float(t))[0, :3]
        out = {}
        for body, pos in self._sky.bodies_km(float(t)).items():
            deg = getattr(self._rules.exclusion, f"{body}_deg")
            if deg >= 0:
                d = pos[0] - obs
                dist = float(np.linalg.norm(d))
                half = float(np.arcsin(min(1.0, self._sky.radii_km[body] / dist)))
                out[body] = (rot.T @ d / dist, half + np.radians(deg))
        return out

    def in_window(self, t) -> np.ndarray:
        """Whether the sensor is tasked on the target at times t (K,) TU -> (K,) bool."""
        tt = np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1)
        if self.revisit_hours <= 0:
            return np.ones(tt.shape, dtype=bool)
        h = tt * (TU_S / 3600.0) - self.first_window_hours
        return (h >= 0) & (np.mod(h, self.revisit_hours) <= self.window_hours)

    def passes(self, times: np.ndarray, states: np.ndarray):
        """Visible samples inside the tasking windows, as contiguous runs (sample at <= 5 min).
        MeasurementError when the target comes within :data:`MIN_SEPARATION_KM` of the observer
        (the same orbit and phase: no line of sight)."""
        tt, x = checked_pass_samples(self._name(), times, states)
        tgt, obs = self._inertial(x, tt)
        sep = np.linalg.norm(tgt[:, :3] - obs[:, :3], axis=1)
        k = int(np.argmin(sep))
        if not sep[k] >= MIN_SEPARATION_KM:
            raise MeasurementError(f"{self._who()}: the target comes within {sep[k]:.3g} km of the observer "
                                   f"(at {tt[k] * TU_S / 86400.0:.3f} days): a telescope cannot observe an object at "
                                   "its own place; give the observer another orbit, phase or state_km")
        return passes_from_mask(tt, self._allowed(tgt, obs, tt) & self.in_window(tt))

    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        """Unit synodic vectors (N, 3) along (RA, Dec) pairs (N, 2) rad at t (scalar or (N,) TU).

        Light time is not undone (see ``line_of_sight_tolerance_lu``); extra columns are ignored.
        """
        ang = np.asarray(angles, dtype=float)
        if ang.ndim != 2 or ang.shape[1] < 2:
            raise MeasurementError(f"{self._who()}: angles must have shape (N, 2), got {ang.shape}")
        if not np.all(np.isfinite(ang[:, :2])):
            raise MeasurementError(f"{self._who()}: angles contain NaN or infinity")
        tt = self._check_times(t, ang.shape[0])
        rot = np.broadcast_to(self._sky.rotation(tt), (ang.shape[0], 3, 3))
        return np.einsum("nji,nj->ni", rot, unit_of_radec(ang[:, 0], ang[:, 1]))

    def inertial_frame(self):
        """The frame RA/Dec are measured in, for exports: GCRF (ephemeris) or the idealised
        equatorial frame (CR3BP)."""
        from cistrack.astro.inertial_frame import InertialFrame
        from .frames import EquatorialFrameModel
        if isinstance(self._sky, RealSky):
            frame = self._sky.frame
            return InertialFrame(name="GCRF", ccsds=True, from_synodic=frame.synodic_to_gcrs,
                                 description="GCRS from the real Earth-Moon rotating frame (DE421)")
        return EquatorialFrameModel(self._epoch, self.moon_phase_deg).inertial_frame()

    # -- simulation -----------------------------------------------------------------------------
    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        """Noisy measurements of a truth trajectory: states (K, 6) synodic at times (K,) TU."""
        x = self._check_states(states)
        tt = np.asarray(times, dtype=float).reshape(-1)
        if tt.shape[0] != x.shape[0]:
            raise MeasurementError(f"{self._who()}: {tt.shape[0]} times for {x.shape[0]} states")
        values, s = noisy_measurements(self, x, tt, rng)
        meta = {"sensor": "space-telescope", "epoch": self.epoch, "measurement": "radec",
                "frame": self._sky.name, "observer": self.orbit or "state_km",
                "light_time": self.light_time}
        return MeasurementSet(tt, values, s, self.names, meta)


@hookimpl
def cistrack_register(registry):
    registry.add("sensor", "space-telescope", SpaceTelescope)
