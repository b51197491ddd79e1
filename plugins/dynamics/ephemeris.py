"""Ephemeris dynamics: Earth, Moon and Sun from JPL DE421, registered as dynamics "ephemeris".

States in and out are nondimensional synodic states of the *real* Earth-Moon rotating frame
(:mod:`cistrack.astro.earth_moon`: barycentric, x to the Moon, z along its orbital angular
momentum, constant LU/TU scaling), so filters, IOD and sensors use this model exactly like
``cr3bp``. Inside, each propagate call converts the states to geocentric GCRS (scaled to LU, VU,
TU), integrates them with the compiled per-particle DOP853 of :mod:`cistrack.propagation`
(right-hand sides in :mod:`.ephemeris_rhs` and :mod:`.ephemeris_point_mass_rhs`: point-mass
Earth, Moon and Sun, optional Earth J2 and cannonball radiation pressure, the ephemeris evaluated
in the kernel from DE421's records over the run's window) and converts the outputs back.

Impacts: the Earth's surface (fixed at the geocentre) and the Moon's (moving with DE421) stop a
particle as in ``cr3bp``; it is frozen at the impact point, in the rotating frame at that time.

Time: t = 0 is the scenario's UTC ``epoch`` (converted once to TDB by
:mod:`cistrack.astro.timescales`); t advances at the TT rate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack import units
from cistrack.interfaces.component import check_int, check_range
from cistrack.astro.ephemeris import DAY_S, ChebyshevSeries
from cistrack.errors import StateError
from cistrack.astro.earth_moon import EarthMoonFrame
from cistrack.api import hookimpl
from cistrack.interfaces.dynamics import Body, Propagation
from cistrack.astro.primaries import EARTH_RADIUS_KM, MOON_RADIUS_KM
from cistrack.propagation import CompiledDynamics

from .ephemeris_point_mass_rhs import ephemeris_point_mass_rhs
from .ephemeris_rhs import (MOON_ACCELERATION_BOUND_KMS2, MOON_SPEED_BOUND_KMS, P_SRP, ephemeris_body_position, ephemeris_rhs,
                           pack_params)

__all__ = ["EphemerisDynamics", "SOLAR_PRESSURE_N_M2"]

RECORD_WINDOWS_KEPT = 4
"""Windows of DE421 records a model and its copies keep (:meth:`EphemerisDynamics._build_params`)."""

SOLAR_PRESSURE_N_M2: float = 4.56e-6
"""Solar radiation pressure on a perfect absorber at 1 AU, N/m^2."""


@dataclass(frozen=True)
class _RealFrameBody(Body):
    """A primary on the x axis of the real Earth-Moon frame at ``x_fraction`` of the distance."""

    x_fraction: float = 0.0
    frame: Any = field(default=None, compare=False, repr=False)

    def position_at(self, t) -> np.ndarray:
        """Synodic position (3,) LU at ``t`` (TU)."""
        d = float(self.frame.axes(float(t)).distance[0]) / units.LU_KM
        return np.array([self.x_fraction * d, 0.0, 0.0])


class EphemerisDynamics(CompiledDynamics):
    """Earth, Moon and Sun point masses from DE421 (+ optional J2, SRP), real rotating frame.

    Parameters
    ----------
    epoch : str
        ISO-8601 UTC time of t = 0 (a scenario injects its own top-level ``epoch``).
    sun : bool
        Include the Sun's gravity (third-body term).
    j2 : bool
        Include the Earth's J2 (DE421's values: J2 1.0826e-3, radius 6378.136 km; the pole is the
        GCRS z axis rotated to the celestial intermediate pole at the epoch).
    srp_area_to_mass_m2_kg : float
        Cannonball solar radiation pressure: area / mass, m^2/kg (0 disables; no eclipses).
    srp_reflectivity : float
        Radiation pressure coefficient C_R (1 absorber, 2 mirror).
    area_to_mass_m2_kg : float
        Cannonball radiation pressure given as the product C_R A/m, m^2/kg, added to
        ``srp_reflectivity * srp_area_to_mass_m2_kg``; the parameter a fit estimates
        (:meth:`with_parameters`). Negative values are unphysical but accepted, so that a
        least-squares estimate near zero is not biased by a bound. 0 (default): none.
    rtol, atol : float
        Per-particle integration tolerances (nondimensional, inertial LU/VU).
    earth_radius_km, moon_radius_km : float
        Impact radii, km (0 disables impacts on that body); defaults from :mod:`cistrack.astro.primaries`.
    window_days : float
        Ephemeris records handed to the kernel cover at least this many days either side of the
        epoch; a propagation reaching outside widens the window.
    max_steps : int
        Step limit per particle and call.
    """

    rhs = ephemeris_rhs
    body_motion = ephemeris_body_position

    def __init__(self, epoch: str = "2026-01-01T00:00:00Z", sun: bool = True, j2: bool = False,
                 srp_area_to_mass_m2_kg: float = 0.0, srp_reflectivity: float = 1.3,
                 area_to_mass_m2_kg: float = 0.0, rtol: float = 1e-12, atol: float = 2e-11, earth_radius_km: float = EARTH_RADIUS_KM,
                 moon_radius_km: float = MOON_RADIUS_KM, window_days: float = 40.0,
                 max_steps: int = 5_000_000):
        try:
            when = units.parse_utc(epoch)
        except (ValueError, TypeError) as exc:
            self._fail("epoch", epoch, f"must be an ISO-8601 UTC time ({exc})")
        if not (1900 <= when.year <= 2052):
            self._fail("epoch", epoch, "must lie within DE421's span (years 1900 to 2052)")
        self.epoch = units.format_utc(when)
        for name, flag in (("sun", sun), ("j2", j2)):
            if not isinstance(flag, bool):
                self._fail(name, flag, "must be true or false")
        self.sun = sun
        self.j2 = j2
        self.srp_area_to_mass_m2_kg = check_range(self, "srp_area_to_mass_m2_kg", srp_area_to_mass_m2_kg, 0.0, 1e3)
        self.srp_reflectivity = check_range(self, "srp_reflectivity", srp_reflectivity, 0.0, 2.0)
        self.area_to_mass_m2_kg = check_range(self, "area_to_mass_m2_kg", area_to_mass_m2_kg, -1e3, 1e3)
        self.rtol = check_range(self, "rtol", rtol, 1e-15, 1e-2)
        self.atol = check_range(self, "atol", atol, 1e-18, 1e-2)
        self.earth_radius_km = check_range(self, "earth_radius_km", earth_radius_km, 0.0, 1e5)
        self.moon_radius_km = check_range(self, "moon_radius_km", moon_radius_km, 0.0, 1e5)
        self.window_days = check_range(self, "window_days", window_days, 1.0, 20_000.0)
        self.max_steps = check_int(self, "max_steps", max_steps, minimum=1)
        self._frame: EarthMoonFrame | None = None
        self._params_cache: np.ndarray | None = None
        self._window: tuple[float, float] = (0.0, 0.0)
        self._records: dict = {}  # shared with the copies of with_parameters (see _build_params)

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_frame"] = None
        state["_params_cache"] = None
        state["_records"] = {}
        state["_window"] = (0.0, 0.0)
        return state

    # -- frame and parameters ---------------------------------------------------------------------
    @property
    def frame(self) -> EarthMoonFrame:
        """The real Earth-Moon rotating frame whose t = 0 is :attr:`epoch`."""
        if self._frame is None:
            self._frame = EarthMoonFrame.from_utc(self.epoch)
        return self._frame

    @property
    def mu(self) -> float:
        """DE421's Earth-Moon mass ratio (the real frame's barycentre)."""
        return self.frame.mu

    def _ensure_window(self, t_lo: float, t_hi: float) -> None:
        half = float(units.days_to_tu(self.window_days))
        first, last = self._coverage(t_lo, t_hi)
        lo, hi = max(min(t_lo, -half), first), min(max(t_hi, half), last)
        if self._params_cache is not None and self._window[0] <= lo and hi <= self._window[1]:
            return
        if self._params_cache is not None:  # widen generously so repeated calls do not rebuild
            lo = max(min(lo, self._window[0] - half), first)
            hi = min(max(hi, self._window[1] + half), last)
        self._params_cache = self._build_params(lo, hi)
        self._window = (lo, hi)

    def _coverage(self, t_lo: float, t_hi: float) -> tuple[float, float]:
        """The span of DE421 in TU from the epoch (the body tables are padded only within it);
        StateError naming the dates when ``[t_lo, t_hi]`` (TU) leaves it."""
        eph = self.frame.ephemeris
        o1, o2 = self.frame.epoch_tdb
        first = ((eph.first_jd - o1) - o2) * DAY_S / units.TU_S
        last = ((eph.last_jd - o1) - o2) * DAY_S / units.TU_S
        if t_lo < first or t_hi > last:
            epoch = units.parse_utc(self.epoch)
            when = [units.format_utc(units.tu_to_utc(epoch, t))[:10] for t in (t_lo, t_hi, first, last)]
            raise StateError(f"{self._label()}: the propagation from {when[0]} to {when[1]} leaves the DE421 "
                             f"ephemeris, which covers {when[2]} to {when[3]}; give times within it")
        return first, last

    def _build_params(self, t_lo: float, t_hi: float) -> np.ndarray:
        """The packed parameters for ``[t_lo, t_hi]`` TU: this model's constants, then DE421's
        records of that window, which depend on the window alone. Those are kept in a table shared
        with this model's copies (:meth:`with_parameters`): a fit that solves for the area-to-mass
        ratio makes a copy per trial value, and each had rebuilt the same records (8,839 copies
        and 17,803 builds in one fit with a burn, a third of its time)."""
        const = self._constants()
        key = (t_lo, t_hi, self.frame.epoch_tdb)
        records = self._records.get(key)
        if records is None:
            records = self._pack(const, t_lo, t_hi)[const.size:]
            records.flags.writeable = False
            if len(self._records) >= RECORD_WINDOWS_KEPT:
                self._records.pop(next(iter(self._records)))
            self._records[key] = records
        return np.concatenate([const, records])

    def _pack(self, const: np.ndarray, t_lo: float, t_hi: float) -> np.ndarray:
        """:func:`pack_params` of DE421's Moon and Sun-minus-barycentre over ``[t_lo, t_hi]`` TU."""
        frame = self.frame
        eph = frame.ephemeris
        origin = frame.epoch_tdb
        s_lo, s_hi = t_lo * units.TU_S, t_hi * units.TU_S
        moon = eph.series("moon", origin, s_lo, s_hi)
        sun = eph.series("sun", origin, s_lo, s_hi)
        emb = eph.series("earthmoon", origin, s_lo, s_hi)
        if sun.start_s != emb.start_s or sun.coefficients.shape[0] != emb.coefficients.shape[0]:
            raise RuntimeError("DE421's Sun and Earth-Moon barycentre records are not aligned")
        ncoef = max(sun.coefficients.shape[2], emb.coefficients.shape[2])
        diff = np.zeros((emb.coefficients.shape[0], 3, ncoef))
        diff[:, :, :sun.coefficients.shape[2]] += sun.coefficients
        diff[:, :, :emb.coefficients.shape[2]] -= emb.coefficients
        sun_minus_emb = ChebyshevSeries(sun.start_s, sun.length_s, diff)
        return pack_params(const, moon, sun_minus_emb, units.LU_KM, units.TU_S)

    def _constants(self) -> np.ndarray:
        """The model's constants (12,) in the packed parameters' units (LU, TU)."""
        eph = self.frame.ephemeris
        lu, tu = units.LU_KM, units.TU_S
        gm = lu ** 3 / tu ** 2
        pole = self._pole()
        srp_kms2 = self._radiation_coefficient() * SOLAR_PRESSURE_N_M2 / 1000.0
        moon_body = -1
        if self.moon_radius_km > 0:
            moon_body = 1 if self.earth_radius_km > 0 else 0
        const = np.array([
            eph.gm_earth_km3s2 / gm, eph.gm_moon_km3s2 / gm,
            eph.gm_sun_km3s2 / gm if self.sun else 0.0,
            eph.j2_earth if self.j2 else 0.0, eph.earth_radius_km / lu,
            pole[0], pole[1], pole[2],
            srp_kms2 * tu ** 2 / lu, eph.au_km / lu, eph.earth_share, float(moon_body)])
        return const

    def _pole(self) -> np.ndarray:
        """Unit vector of the Earth's rotation axis (CIP) in GCRS at the epoch (IAU 2006/2000A)."""
        if not self.j2:
            return np.array([0.0, 0.0, 1.0])
        import erfa

        jd1, jd2 = self.frame.epoch_tdb
        x, y = erfa.bpn2xy(erfa.pnm06a(jd1, jd2))
        return np.array([x, y, math.sqrt(max(0.0, 1.0 - x * x - y * y))])

    def _radiation_coefficient(self) -> float:
        """C_R A/m, m^2/kg: ``srp_reflectivity * srp_area_to_mass_m2_kg``, plus ``area_to_mass_m2_kg``
        when that is not 0 (a branch, so that the product alone keeps its exact value)."""
        c = self.srp_reflectivity * self.srp_area_to_mass_m2_kg
        return c + self.area_to_mass_m2_kg if self.area_to_mass_m2_kg != 0.0 else c

    def _rhs(self) -> Any:
        """The point-mass right-hand side when J2 and radiation pressure are off (same numbers)."""
        return ephemeris_rhs if self.j2 or self._radiation_coefficient() else ephemeris_point_mass_rhs

    # -- solve-for parameters ---------------------------------------------------------------------
    solve_for_parameters = ("area_to_mass_m2_kg",)
    """Names a least-squares fit may estimate (:func:`cistrack.least_squares.fit_orbit`)."""

    def parameter(self, name: str) -> float:
        """The current value of solve-for parameter ``name``: ``area_to_mass_m2_kg`` is the total
        C_R A/m (m^2/kg) of the radiation pressure, however it was given."""
        if name not in self.solve_for_parameters:
            raise StateError(f"{self._label()}: no solve-for parameter {name!r}; known: "
                             + ", ".join(self.solve_for_parameters))
        return float(self._radiation_coefficient())

    def with_parameters(self, **values: float) -> "EphemerisDynamics":
        """A copy whose solve-for parameters take ``values`` (``area_to_mass_m2_kg``: the total
        C_R A/m, m^2/kg, replacing ``srp_reflectivity * srp_area_to_mass_m2_kg``); it shares this
        model's frame and ephemeris records, with its own constants."""
        import copy

        for name, v in values.items():
            self.parameter(name)
            if not np.isfinite(v) or abs(v) > 1e3:
                self._fail(name, v, "must be a finite number in [-1000, 1000]")
        new = copy.copy(self)  # through __getstate__: the copy starts without this model's caches
        new._frame, new._records = self.frame, self._records  # the same epoch's frame and DE421 records
        if "area_to_mass_m2_kg" in values:
            new.srp_area_to_mass_m2_kg = 0.0
            new.area_to_mass_m2_kg = float(values["area_to_mass_m2_kg"])
        if self._params_cache is not None:
            new._params_cache = self._params_cache.copy()
            srp = new._radiation_coefficient() * SOLAR_PRESSURE_N_M2 / 1000.0
            new._params_cache[P_SRP] = srp * units.TU_S ** 2 / units.LU_KM
        return new

    def params_vector(self) -> np.ndarray:
        """The packed constants and DE421 records (see :mod:`.ephemeris_rhs`), (P,) float64."""
        if self._params_cache is None:
            self._ensure_window(0.0, 0.0)
        return self._params_cache

    # -- bodies -----------------------------------------------------------------------------------
    @property
    def primaries(self) -> tuple[Body, ...]:
        """Earth and Moon with DE421's mass fractions and radii in LU (radius 0: no impacts).
        ``position`` is the synodic position at t = 0; :meth:`Body.position_at` follows the
        real Earth-Moon distance (the bodies move along the x axis as it changes)."""
        mu = self.mu
        d0 = float(self.frame.axes(0.0).distance[0]) / units.LU_KM
        return (
            _RealFrameBody("Earth", np.array([-mu * d0, 0.0, 0.0]), float(units.km_to_lu(self.earth_radius_km)),
                           1.0 - mu, -mu, self.frame),
            _RealFrameBody("Moon", np.array([(1.0 - mu) * d0, 0.0, 0.0]), float(units.km_to_lu(self.moon_radius_km)),
                           mu, 1.0 - mu, self.frame))

    def _bodies_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Kernel bodies: the Earth at rest; the Moon (DE421), its speed and acceleration bounded (MOON_*_BOUND_*)."""
        moon = (units.kms_to_vu(MOON_SPEED_BOUND_KMS), MOON_ACCELERATION_BOUND_KMS2 * units.TU_S ** 2 / units.LU_KM)
        rva = [(r, va) for r, va in ((self.earth_radius_km, (0.0, 0.0)), (self.moon_radius_km, moon)) if r > 0]
        pos = np.zeros((max(len(rva), 1), 5))
        pos[:len(rva), 3:] = np.reshape([va for _, va in rva], (-1, 2))
        return pos, np.array([float(units.km_to_lu(r)) for r, _ in rva])

    # -- conversions ------------------------------------------------------------------------------
    def to_inertial(self, states: np.ndarray, t) -> np.ndarray:
        """Synodic states (N, 6) [LU, VU] at ``t`` (TU) -> kernel states (N, 6): GCRS in LU, VU."""
        return self.frame.synodic_to_gcrs(states, t, unit="lu")

    def from_inertial(self, states: np.ndarray, t) -> np.ndarray:
        """Kernel states (N, 6) GCRS [LU, VU] at ``t`` (TU) -> synodic states (N, 6) [LU, VU]."""
        return self.frame.gcrs_to_synodic(states, t, unit="lu")

    # -- Dynamics ---------------------------------------------------------------------------------
    def propagate(self, states: np.ndarray, t0: float, times: Any, *,
                  rtol: float | None = None, atol: float | None = None,
                  steps: np.ndarray | None = None) -> Propagation:
        """Propagate synodic ``states`` (N, 6) from ``t0`` to ``times`` (scalar or (K,), TU).

        As :meth:`cistrack.propagation.CompiledDynamics.propagate`, with states in the real
        rotating frame; particles that hit the Earth or the Moon are frozen at the impact point
        (rotating-frame coordinates at the impact time).
        """
        arr = self._check_states(states)
        t_out = np.atleast_1d(np.asarray(times, dtype=np.float64)).reshape(-1)
        if t_out.size == 0 or not (np.isfinite(t0) and np.all(np.isfinite(t_out))):
            raise StateError(f"{self._label()}: t0 and times must be finite, and at least one time given")
        span = np.concatenate(([float(t0)], t_out))
        self._ensure_window(float(span.min()), float(span.max()))
        inertial = self.to_inertial(arr, float(t0)) if arr.shape[0] else arr
        prop = CompiledDynamics.propagate(self, inertial, t0, t_out, rtol=rtol, atol=atol, steps=steps)
        out = self.frame.gcrs_to_synodic_each(prop.states, t_out, unit="lu") if arr.shape[0] \
            else np.empty_like(prop.states)
        dead = ~prop.alive
        if np.any(dead):
            idx = np.nonzero(dead)[0]
            at_impact = self.from_inertial(prop.states[-1, idx], prop.impact_time[idx])
            direction = 1.0 if t_out[-1] >= t0 else -1.0
            for k, tk in enumerate(t_out):
                hit = direction * (tk - prop.impact_time[idx]) >= 0.0
                out[k, idx[hit]] = at_impact[hit]
        prop.states = out
        return prop

    def propagate_with_stm(self, state: np.ndarray, t0: float, times) -> tuple[np.ndarray, np.ndarray]:
        """Synodic ``state`` (6,) and its state transition matrix from ``t0`` to ``times`` (K,) TU
        -> (states (K, 6), stms (K, 6, 6)) in the real rotating frame: the variational equations
        integrated in GCRS by the compiled DOP853 (:func:`.ephemeris_variational.synodic_stm`).
        Raises ``PropagationError`` when the trajectory hits a body."""
        from .ephemeris_variational import synodic_stm  # compiles numba code: first use only

        return synodic_stm(self, state, t0, times)

    sensitivity_parameters = ("area_to_mass_m2_kg",)
    """Solve-for parameters whose d x / d p :meth:`propagate_with_sensitivity` integrates."""

    def propagate_with_sensitivity(self, state: np.ndarray, t0: float, times,
                                   name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`propagate_with_stm`, and d x(t_k) / d p (K, 6) (LU, VU per m^2/kg) of the
        solve-for parameter ``name`` ("area_to_mass_m2_kg", the total C_R A/m), the state at
        ``t0`` held: variational equations with the radiation pressure's sensitivity
        (:func:`.ephemeris_variational.synodic_srp_sensitivity`). Raises ``StateError`` for
        another name, and ``PropagationError`` when the trajectory hits a body."""
        from .ephemeris_variational import synodic_srp_sensitivity  # compiles numba code: first use only

        if name not in self.sensitivity_parameters:
            raise StateError(f"{self._label()}: no sensitivity of {name!r}; known: {', '.join(self.sensitivity_parameters)}")
        states, stms, sens = synodic_srp_sensitivity(self, state, t0, times)
        return states, stms, sens * (SOLAR_PRESSURE_N_M2 / 1000.0 * units.TU_S ** 2 / units.LU_KM)

    def dense_trajectory(self, state: np.ndarray, t0: float, t1: float, *,
                         rtol: float | None = None, atol: float | None = None):
        """As :meth:`cistrack.propagation.CompiledDynamics.dense_trajectory` for a synodic
        ``state`` (6,): integrated in GCRS, evaluated states converted back to the real rotating
        frame at their times."""
        arr = self._check_states(state)
        self._ensure_window(min(float(t0), float(t1)), max(float(t0), float(t1)))
        traj = super().dense_trajectory(self.to_inertial(arr, float(t0))[0], t0, t1, rtol=rtol, atol=atol)
        traj.transform = lambda states, times: self.from_inertial(states, times)
        return traj

    def inertial_derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Derivatives of kernel states (N, 6) (geocentric GCRS, LU and VU) at ``t`` (TU) ->
        (N, 6) [VU, VU/TU]: the compiled right-hand side itself."""
        self._ensure_window(float(t), float(t))
        return super().derivatives(t, states)

    def propagate_inertial(self, states: np.ndarray, t0: float, times: Any, *,
                           rtol: float | None = None, atol: float | None = None) -> Propagation:
        """Propagate kernel states (N, 6) (geocentric GCRS, LU and VU) from ``t0`` to ``times``
        (TU) with no frame conversion: the compiled integrator itself (impacts as in
        :meth:`propagate`, states frozen in GCRS)."""
        t_out = np.atleast_1d(np.asarray(times, dtype=np.float64)).reshape(-1)
        span = np.concatenate(([float(t0)], t_out))
        if np.all(np.isfinite(span)):
            self._ensure_window(float(span.min()), float(span.max()))
        return super().propagate(states, t0, t_out, rtol=rtol, atol=atol)

    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of synodic ``states`` (N, 6) at ``t`` (TU) -> (N, 6) [VU, VU/TU].

        The inertial acceleration of the compiled right-hand side, less the frame's: barycentre
        acceleration, Euler (omega' x rho, omega' by a central difference of the analytic omega
        over +-1e-4 TU), Coriolis and centrifugal terms.
        """
        arr = self._check_states(states)
        t = float(t)
        inertial = self.to_inertial(arr, t)
        acc = self.inertial_derivatives(t, inertial)[:, 3:] * (units.LU_KM / units.TU_S ** 2)  # km/s^2
        frame = self.frame
        ax = frame.axes(t)
        rot = ax.rotation[0]
        om = ax.omega[0]
        h = 1e-4
        omd = (frame.axes(t + h).omega[0] - frame.axes(t - h).omega[0]) / (2.0 * h * units.TU_S)
        jd1, jd2 = frame.epoch_tdb
        bacc = frame.mu * frame.ephemeris.moon_acceleration(jd1, jd2 + t * units.TU_S / DAY_S)
        rho = arr[:, :3] @ rot.T * units.LU_KM
        rhod = arr[:, 3:] @ rot.T * units.VU_KMS
        rel = (acc - bacc - np.cross(omd, rho) - 2.0 * np.cross(om, rhod)
               - np.cross(om, np.cross(om, rho)))
        out = np.empty_like(arr)
        out[:, :3] = arr[:, 3:]
        out[:, 3:] = rel @ rot * (units.TU_S / units.VU_KMS)
        return out


@hookimpl
def cistrack_register(registry):
    registry.add("dynamics", "ephemeris", EphemerisDynamics)
