"""The real Earth-Moon rotating frame, and synodic <-> GCRS state transforms.

Frame at TDB time t, from DE421's geocentric Moon r(t), v(t), a(t) (:mod:`cistrack.astro.ephemeris`):

- origin: the Earth-Moon barycentre b = mu r, mu = m_Moon / (m_Earth + m_Moon) of DE421
  (1/(1 + EMRAT) = 0.0121505843; the CR3BP's constant is 0.0121505820);
- x = r / |r| (Earth to Moon), z = (r x v) / |r x v| (the Moon's orbital angular momentum),
  y = z x x; the rotation C = [x y z] maps frame components to GCRS components;
- angular velocity (GCRS components) omega = (h / d^2) z + (d (a . z) / h) x, with d = |r|,
  h = |r x v|: the first term turns x with the Moon, the second tilts the orbit plane about the
  Earth-Moon line as the Sun and the Earth's figure pull the Moon out of plane.

Scalings (both exact transforms, inverses of each other):

- ``synodic`` (the states cistrack carries, filters and IOD see): constant units, position
  rho = C^T (R - b) / LU and velocity rho' = C^T (V - b' - omega x (R - b)) / VU, with the CR3BP's
  LU = 384,400 km, TU = 375,149 s, VU = LU/TU (:mod:`cistrack.units`). The Earth and Moon sit at
  (-mu d/LU, 0, 0) and ((1-mu) d/LU, 0, 0): on the x axis, moving along it as d(t) varies
  (356,000-407,000 km).
- ``pulsating``: position scaled by the instantaneous distance d(t) and velocity by the
  instantaneous d(t) * (h / d^2) (the local "VU"), velocity relative to the pulsating frame:
  R = b + d C rho, V = b' + d' C rho + (h / d) C rho' + omega x (d C rho). The Earth and Moon sit
  at (-mu, 0, 0) and (1 - mu, 0, 0) exactly, which makes CR3BP catalog states good initial
  guesses for the ephemeris model.

Time: t is TU since a TDB origin (jd1, jd2); a scenario's UTC epoch is converted once to TDB by
:mod:`cistrack.astro.timescales` (:meth:`EarthMoonFrame.from_utc`), and TDB is then advanced at the TT
rate (the periodic TDB - TT term, <= 1.7 ms, moves the Moon by <= 2 m and is neglected).
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

import numpy as np

from cistrack import units
from cistrack.astro.ephemeris import DAY_S, DE421, de421
from cistrack.astro.frame_kernels import gcrs_to_synodic_into, synodic_to_gcrs_into
from cistrack.astro.kept_by_time import kept_or_evaluated

__all__ = ["EarthMoonFrame", "FrameAxes"]


@dataclass(frozen=True)
class FrameAxes:
    """The real rotating frame at K times (all GCRS components, km, s).

    Attributes
    ----------
    rotation : (K, 3, 3)   columns are the frame's x, y, z axes
    origin : (K, 3)        barycentre position, km
    origin_velocity : (K, 3)  barycentre velocity, km/s
    omega : (K, 3)         frame angular velocity, rad/s
    distance : (K,)        Earth-Moon distance d, km
    distance_rate : (K,)   d', km/s
    angular_rate : (K,)    h / d^2, rad/s
    """

    rotation: np.ndarray
    origin: np.ndarray
    origin_velocity: np.ndarray
    omega: np.ndarray
    distance: np.ndarray
    distance_rate: np.ndarray
    angular_rate: np.ndarray


def _read_only(ax: FrameAxes) -> FrameAxes:
    for arr in vars(ax).values():
        arr.setflags(write=False)
    return ax


def _broadcast(states, t) -> tuple[np.ndarray, np.ndarray, bool]:
    s = np.asarray(states, dtype=float)
    single = s.ndim == 1
    s = np.atleast_2d(s)
    if s.shape[-1] != 6 or s.ndim != 2:
        raise ValueError(f"states must have shape (6,) or (N, 6), got {np.shape(states)}")
    tt = np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1)
    if tt.size not in (1, s.shape[0]):
        raise ValueError(f"t must be a scalar or have one time per state ({s.shape[0]}), got {tt.size}")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(tt))):
        raise ValueError("states and times must be finite")
    return s, np.broadcast_to(tt, (s.shape[0],)) if tt.size > 1 else tt, single


def _to_synodic_each(s: np.ndarray, stack: tuple[np.ndarray, ...], mul_r: float, mul_v: float) -> np.ndarray:
    """GCRS states (K, N, 6) and the frame at each of their K times (rotation (K, 3, 3), origin,
    origin velocity, omega (K, 3)) -> synodic (K, N, 6): one pass of the compiled loop over all
    K N states, each with its time's frame (the same operations as one time at a time)."""
    k, n = s.shape[0], s.shape[1]
    flat = np.ascontiguousarray(s).reshape(k * n, 6)
    rot, origin, origin_v, omega = (np.repeat(a, n, axis=0) if n != 1 else a for a in stack)
    out = np.empty_like(flat)
    gcrs_to_synodic_into(flat, mul_r, mul_v, rot, origin, origin_v, omega, units.LU_KM, units.VU_KMS, out)
    return out.reshape(s.shape)


def _unit_scales(unit: str) -> tuple[float, float]:
    """(position, velocity) km per unit of GCRS states given in ``unit`` ("km" or "lu")."""
    if unit == "km":
        return 1.0, 1.0
    if unit == "lu":
        return float(units.LU_KM), float(units.VU_KMS)
    raise ValueError(f"unit must be 'km' or 'lu' (GCRS states in km and km/s, or in LU and VU), got {unit!r}")


AXES_KEPT = 4096
"""Single times whose frame :meth:`EarthMoonFrame.axes` keeps (about 1 kB each; not pickled)."""

SETS_KEPT = 64
"""Vectors of times whose frames :meth:`EarthMoonFrame.axes` keeps (a least squares asks for the
frames at its arc's measurement times at every iteration and Jacobian column)."""

SET_SIZE_KEPT = 2048
"""The longest vector of times kept (about 350 kB of axes); longer ones are evaluated each time."""

STACKS_KEPT = 16
"""Vectors of times (at most :data:`AXES_KEPT`) whose kept single-time frames
:meth:`EarthMoonFrame.gcrs_to_synodic_each` keeps stacked (up to about 600 kB each)."""

FRAMES_SHARED = 8
"""(epoch, ephemeris) pairs whose kept times are shared by all their frames (the oldest dropped
first)."""


@dataclass(frozen=True)
class _KeptAxes:
    """What the frames of one epoch and ephemeris keep: axes by single time, and by vector of times
    (its bytes)."""

    ephemeris: object
    singles: dict
    sets: dict
    stacks: dict


_kept_by_frame: dict[tuple, _KeptAxes] = {}
"""(TDB epoch, id of the ephemeris) -> what every frame of that epoch and ephemeris keeps. A fit
builds the frame again for each attempt and each trial C_R A/m (43 frames in the 2025-010D fit),
and each had evaluated DE421 at the same times afresh; the ephemeris is held with the entry, so
its id is not reused while the entry lives."""


def _shared_kept(epoch_tdb: tuple[float, float], ephemeris) -> _KeptAxes:
    """The kept axes of every frame with this epoch and ephemeris."""
    entry = kept_or_evaluated(_kept_by_frame, (epoch_tdb, id(ephemeris)), FRAMES_SHARED,
                              lambda: _KeptAxes(ephemeris, {}, {}, {}))
    return entry if entry.ephemeris is ephemeris else _KeptAxes(ephemeris, {}, {}, {})


class EarthMoonFrame:
    """Transforms between the real Earth-Moon rotating frame and GCRS (see module docstring).

    Parameters
    ----------
    epoch_tdb : (float, float)
        TDB Julian date (two parts) of t = 0.
    ephemeris : DE421, optional
        Reader to use (default: the process-wide DE421).
    """

    def __init__(self, epoch_tdb: tuple[float, float], ephemeris: DE421 | None = None):
        self.epoch_tdb = (float(epoch_tdb[0]), float(epoch_tdb[1]))
        self.ephemeris = ephemeris if ephemeris is not None else de421()
        self.mu = self.ephemeris.earth_share
        self._kept = _shared_kept(self.epoch_tdb, self.ephemeris)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        del state["_kept"]  # kept evaluations are rebuilt on use, not shipped to other processes
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._kept = _shared_kept(self.epoch_tdb, self.ephemeris)

    @classmethod
    def from_utc(cls, epoch: datetime | str, ephemeris: DE421 | None = None) -> "EarthMoonFrame":
        """Frame whose t = 0 is the UTC ``epoch`` (datetime or ISO-8601 text)."""
        from cistrack.astro import timescales

        jd1, jd2 = timescales.tdb_jd(units.parse_utc(epoch))
        return cls((float(np.ravel(jd1)[0]), float(np.ravel(jd2)[0])), ephemeris)

    def tdb_days(self, t) -> np.ndarray:
        """Days after the TDB origin of times ``t`` (TU), (K,)."""
        return np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1) * (units.TU_S / DAY_S)

    def axes(self, t) -> FrameAxes:
        """The frame at times ``t`` (scalar or (K,) TU) as :class:`FrameAxes` with K entries.

        The frame at a single time is kept (up to :data:`AXES_KEPT` times; arrays read-only) and
        returned again for the same time: a filter converts its particles at the times it stops
        at, again and again (a propagation ends where the next one starts, and re-anchoring
        revisits every measurement time), and each evaluation of DE421 costs about 0.4 ms.
        Several times at once are evaluated together (vectorised over the times, which rounds a
        few values differently from one time at a time: not mixed with the kept ones), and kept
        as a set (up to :data:`SETS_KEPT` vectors of at most :data:`SET_SIZE_KEPT` times). Every
        frame of the same epoch and ephemeris shares what is kept."""
        tt = np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1)
        if tt.size == 1:
            return kept_or_evaluated(self._kept.singles, float(tt[0]), AXES_KEPT,
                                     lambda: _read_only(self._evaluate_axes(tt)))
        if tt.size > SET_SIZE_KEPT:
            return self._evaluate_axes(tt)
        return kept_or_evaluated(self._kept.sets, tt.tobytes(), SETS_KEPT, lambda: _read_only(self._evaluate_axes(tt)))

    def _evaluate_axes(self, t: np.ndarray) -> FrameAxes:
        jd1, jd2 = self.epoch_tdb
        dd = self.tdb_days(t)
        r, v = self.ephemeris.moon(jd1, jd2 + dd)
        a = self.ephemeris.moon_acceleration(jd1, jd2 + dd)
        r, v, a = np.atleast_2d(r), np.atleast_2d(v), np.atleast_2d(a)
        d = np.linalg.norm(r, axis=1)
        hv = np.cross(r, v)
        h = np.linalg.norm(hv, axis=1)
        ex = r / d[:, None]
        ez = hv / h[:, None]
        ey = np.cross(ez, ex)
        rot = np.stack([ex, ey, ez], axis=2)
        rate = h / d ** 2
        tilt = d * np.sum(a * ez, axis=1) / h
        omega = rate[:, None] * ez + tilt[:, None] * ex
        return FrameAxes(rotation=rot, origin=self.mu * r, origin_velocity=self.mu * v, omega=omega,
                         distance=d, distance_rate=np.sum(r * v, axis=1) / d, angular_rate=rate)

    # -- constant-unit synodic states (what cistrack carries) ---------------------------------
    def synodic_to_gcrs(self, states, t, *, unit: str = "km") -> np.ndarray:
        """Synodic states (N, 6) [LU, VU] at ``t`` (scalar or (N,) TU) -> GCRS (N, 6) in km and
        km/s (``unit="km"``) or in LU and VU (``unit="lu"``: the ephemeris model's kernel states,
        the km result divided by LU_KM and VU_KMS).

        A (6,) state gives a (6,) result.
        """
        scale_r, scale_v = _unit_scales(unit)
        s, tt, single = _broadcast(states, t)
        ax = self.axes(tt)
        out = np.empty_like(s)
        synodic_to_gcrs_into(s, ax.rotation, ax.origin, ax.origin_velocity, ax.omega, units.LU_KM, units.VU_KMS,
                             scale_r, scale_v, out)
        return out[0] if single else out

    def gcrs_to_synodic(self, states_km, t, *, unit: str = "km") -> np.ndarray:
        """GCRS states (N, 6) at ``t`` (scalar or (N,) TU), in km and km/s (``unit="km"``) or in
        LU and VU (``unit="lu"``) -> synodic (N, 6) [LU, VU]."""
        scale_r, scale_v = _unit_scales(unit)
        s, tt, single = _broadcast(states_km, t)
        ax = self.axes(tt)
        out = np.empty_like(s)
        gcrs_to_synodic_into(s, scale_r, scale_v, ax.rotation, ax.origin, ax.origin_velocity, ax.omega,
                             units.LU_KM, units.VU_KMS, out)
        return out[0] if single else out

    def gcrs_to_synodic_each(self, states, times, *, unit: str = "km") -> np.ndarray:
        """GCRS states (K, N, 6) at ``times`` (K,) TU (N states at each) -> synodic (K, N, 6) [LU,
        VU], as :meth:`gcrs_to_synodic` at each time, bit for bit. Up to :data:`AXES_KEPT` times the
        frame of each is kept for the next request (a filter's stops, a least squares' measurement
        times), and their stack as well (:data:`STACKS_KEPT` vectors of times): a fit of 881
        observations converts at every one at each propagation, and converting time by time had
        been half its run time. Beyond, more than can be kept, the frames are evaluated
        :data:`SET_SIZE_KEPT` times at once (rounded a few ulp differently from one at a time)."""
        scale_r, scale_v = _unit_scales(unit)
        s = np.asarray(states, dtype=float)
        tt = np.asarray(times, dtype=float).reshape(-1)
        if s.ndim != 3 or s.shape[0] != tt.size or s.shape[-1] != 6:
            raise ValueError(f"states must have shape (K, N, 6) with K = {tt.size} times, got {s.shape}")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(tt))):
            raise ValueError("states and times must be finite")
        if tt.size <= AXES_KEPT:
            stack = kept_or_evaluated(self._kept.stacks, tt.tobytes(), STACKS_KEPT, lambda: self._stacked(tt))
            return _to_synodic_each(s, stack, scale_r, scale_v)
        out = np.empty_like(s)
        for lo in range(0, tt.size, SET_SIZE_KEPT):
            ax = self._evaluate_axes(tt[lo:lo + SET_SIZE_KEPT])
            part = slice(lo, lo + ax.distance.size)
            out[part] = _to_synodic_each(s[part], (ax.rotation, ax.origin, ax.origin_velocity, ax.omega),
                                         scale_r, scale_v)
        return out

    def _stacked(self, tt: np.ndarray) -> tuple[np.ndarray, ...]:
        """(rotation (K, 3, 3), origin, origin velocity, omega (K, 3)): the frame of each of the
        times ``tt`` (K,) as :meth:`axes` gives it for that time alone, stacked (read-only)."""
        each = [self.axes(float(t)) for t in tt]
        stack = tuple(np.concatenate([getattr(a, name) for a in each])
                      for name in ("rotation", "origin", "origin_velocity", "omega"))
        for arr in stack:
            arr.setflags(write=False)
        return stack

    # -- pulsating states (CR3BP-like: Earth and Moon fixed) ----------------------------------
    def pulsating_to_gcrs(self, states, t) -> np.ndarray:
        """Pulsating synodic states (N, 6) at ``t`` (TU) -> GCRS (N, 6) km, km/s."""
        s, tt, single = _broadcast(states, t)
        ax = self.axes(tt)
        rot = np.broadcast_to(ax.rotation, (s.shape[0], 3, 3))
        d = np.broadcast_to(ax.distance, (s.shape[0],))[:, None]
        dd = np.broadcast_to(ax.distance_rate, (s.shape[0],))[:, None]
        vu = d * np.broadcast_to(ax.angular_rate, (s.shape[0],))[:, None]
        crho = np.einsum("nij,nj->ni", rot, s[:, :3])
        out = np.empty_like(s)
        out[:, :3] = ax.origin + d * crho
        out[:, 3:] = (ax.origin_velocity + dd * crho + vu * np.einsum("nij,nj->ni", rot, s[:, 3:])
                      + np.cross(ax.omega, d * crho))
        return out[0] if single else out

    def gcrs_to_pulsating(self, states_km, t) -> np.ndarray:
        """GCRS states (N, 6) km, km/s at ``t`` (TU) -> pulsating synodic states (N, 6)."""
        s, tt, single = _broadcast(states_km, t)
        ax = self.axes(tt)
        rot = np.broadcast_to(ax.rotation, (s.shape[0], 3, 3))
        d = np.broadcast_to(ax.distance, (s.shape[0],))[:, None]
        dd = np.broadcast_to(ax.distance_rate, (s.shape[0],))[:, None]
        vu = d * np.broadcast_to(ax.angular_rate, (s.shape[0],))[:, None]
        rel = s[:, :3] - ax.origin
        crho = rel / d
        relv = s[:, 3:] - ax.origin_velocity - dd * crho - np.cross(ax.omega, rel)
        out = np.empty_like(s)
        out[:, :3] = np.einsum("nji,nj->ni", rot, crho)
        out[:, 3:] = np.einsum("nji,nj->ni", rot, relv) / vu
        return out[0] if single else out

    def moon_synodic(self, t) -> np.ndarray:
        """Synodic positions of the Moon (K, 3) LU at ``t`` (TU): ((1-mu) d / LU, 0, 0)."""
        ax = self.axes(t)
        out = np.zeros((ax.distance.size, 3))
        out[:, 0] = (1.0 - self.mu) * ax.distance / units.LU_KM
        return out
