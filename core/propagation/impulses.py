"""A dynamics model flown with impulsive burns: :class:`ImpulsiveDynamics`.

``ImpulsiveDynamics(base, impulses)`` is a :class:`~cistrack.interfaces.dynamics.Dynamics` that
integrates ``base`` between the burns and adds each :class:`~cistrack.interfaces.maneuvers.Impulse`'s
``dv`` (synodic VU) to the velocity at its time ``t`` (TU). It is how a scenario's truth flies
the burns of its ``[truth.maneuvers]`` plan (docs/maneuvers.md); the filter's model stays
ballistic.

Convention: **the state at exactly ``t_b`` is the pre-burn state**; ``dv`` is added just after.
Forward in time a propagation from ``t0`` applies the burns with ``t0 <= t_b < t`` (a burn at
``t0`` itself is applied, one at the output time is not); backward it subtracts the burns with
``t <= t_b < t0`` (a state asked for at ``t_b`` is again the pre-burn one). Burns whose ``dv``
is exactly zero are skipped, so a plan of zero burns gives the base's numbers bit for bit.

Everything but the burns belongs to the base: :meth:`derivatives` (ballistic), the bodies and
primaries, any other attribute (``epoch``, ``mu``, ``rtol``, ...). A particle that hits a body in
one segment stays dead (frozen at its impact state) for every later output, and the
:class:`~cistrack.interfaces.dynamics.Propagation` reports where and when, as the base does.
:meth:`~ImpulsiveDynamics.propagate_with_stm` chains the base's state transition matrices
across the burns (a constant synodic ``dv`` has the identity as its jump Jacobian), and
``dense_trajectory`` (present when the base has it) returns an :class:`ImpulsiveTrajectory`,
one dense piece per segment.

Solve-for parameters (:mod:`cistrack.least_squares.solve_for_parameters`): the base's, and for
each impulse ``k`` (0-based, in time order as :attr:`ImpulsiveDynamics.impulses` lists them)
``delta_v_{k}_x_ms``, ``delta_v_{k}_y_ms``, ``delta_v_{k}_z_ms``: its synodic components in m/s.
"""
from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, ConfigError, StateError, exception_text
from cistrack.interrupts import plugin_fault
from cistrack.interfaces.component import component_name
from cistrack.interfaces.dynamics import Body, Dynamics, Propagation, check_output_times
from cistrack.interfaces.maneuvers import Impulse, ManeuverPlan
from cistrack.interfaces.transition_matrix import check_stm_request

__all__ = ["ImpulsiveDynamics", "ImpulsiveTrajectory", "delta_v_parameter_names", "fly_plan", "describe_impulse"]

MS_PER_VU = units.VU_KMS * 1000.0
"""Metres per second in one velocity unit."""
_AXES = ("x", "y", "z")


def delta_v_parameter_names(k: int) -> tuple[str, str, str]:
    """The solve-for parameter names of impulse ``k``: ``delta_v_{k}_x_ms`` .. ``_z_ms``."""
    return tuple(f"delta_v_{k}_{a}_ms" for a in _AXES)  # type: ignore[return-value]


def _check_base(base: Any) -> Dynamics:
    if not callable(getattr(base, "propagate", None)) or not callable(getattr(base, "derivatives", None)):
        raise ConfigError(f"ImpulsiveDynamics: base must be a Dynamics model (with propagate and derivatives), "
                          f"got {type(base).__name__}")
    return base


def _check_impulses(impulses: Any) -> tuple[Impulse, ...]:
    if isinstance(impulses, (Impulse, str, bytes)) or not isinstance(impulses, Sequence):
        raise ConfigError(f"ImpulsiveDynamics: impulses must be a sequence of Impulse, got {type(impulses).__name__}")
    bad = [i for i, imp in enumerate(impulses) if not isinstance(imp, Impulse)]
    if bad:
        raise ConfigError(f"ImpulsiveDynamics: impulses[{bad[0]}] is a {type(impulses[bad[0]]).__name__}, "
                          "not an Impulse(t, dv, label)")
    return tuple(sorted(impulses, key=lambda imp: imp.t))  # stable: equal times keep their order


def _merged_burns(impulses: tuple[Impulse, ...]) -> list[tuple[float, np.ndarray]]:
    """(time, summed dv) of the burns that change anything, sorted by time."""
    out: list[tuple[float, np.ndarray]] = []
    for imp in impulses:
        if out and out[-1][0] == imp.t:
            out[-1] = (imp.t, out[-1][1] + imp.dv)
        else:
            out.append((float(imp.t), imp.dv.copy()))
    return [(t, dv) for t, dv in out if np.any(dv != 0.0)]


class ImpulsiveDynamics(Dynamics):
    """``base`` flown with ``impulses`` applied (see the module docstring for the convention).

    Parameters
    ----------
    base : Dynamics
        The ballistic model; an ImpulsiveDynamics given here is unwrapped (its impulses come
        first in the list, then these, all sorted by time).
    impulses : sequence of Impulse
        The burns: time TU since the scenario epoch and ``dv`` (3,) synodic VU.
    """

    carries_steps = False

    def __init__(self, base: Dynamics, impulses: Sequence[Impulse]) -> None:
        base = _check_base(base)
        impulses = _check_impulses(impulses)
        if isinstance(base, ImpulsiveDynamics):
            impulses = _check_impulses(list(base.impulses) + list(impulses))
            base = base.base
        self.base = base
        self.impulses = impulses
        self._burns = _merged_burns(impulses)

    # -- what belongs to the base -----------------------------------------------------------------
    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in ("base", "impulses", "_burns"):
            raise AttributeError(name)
        base = self.__dict__.get("base")
        if base is None:
            raise AttributeError(name)
        return getattr(base, name)

    def _label(self) -> str:  # type: ignore[override]
        base = self.base
        label = base._label() if callable(getattr(base, "_label", None)) else type(base).__name__
        return f"{label} with {len(self.impulses)} impulse(s)"

    @property
    def registry_name(self) -> str:  # type: ignore[override]
        """The base's registered name."""
        return getattr(self.base, "registry_name", "")

    @property
    def primaries(self) -> tuple[Body, ...]:
        return self.base.primaries

    @property
    def bodies(self) -> tuple[Body, ...]:
        return self.base.bodies

    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """The base's (ballistic) derivatives: an impulse is no acceleration."""
        return self.base.derivatives(t, states)

    # -- segments -----------------------------------------------------------------------------------
    def _crossed(self, t0: float, t_end: float) -> list[tuple[float, np.ndarray]]:
        """The burns a flight from ``t0`` to ``t_end`` crosses, in the order it meets them, each
        with the velocity change it makes (``-dv`` backward)."""
        forward = t_end >= t0
        lo, hi = (t0, t_end) if forward else (t_end, t0)
        out = [(t, dv if forward else -dv) for t, dv in self._burns if lo <= t < hi]
        return out if forward else out[::-1]

    def _segments(self, t0: float, t_out: np.ndarray) -> list[tuple[int, float, np.ndarray | None]]:
        """(end index into ``t_out``, end time, velocity change there or None) per segment: the
        outputs ``t_out[k:j]`` of a segment precede its burn (forward an output at the burn's
        time belongs to the segment before it, backward to the one after it)."""
        forward = t_out[-1] >= t0
        s_out = t_out if forward else -t_out
        segs: list[tuple[int, float, np.ndarray | None]] = []
        for t_b, dv in self._crossed(t0, float(t_out[-1])):
            s_b = t_b if forward else -t_b
            j = int(np.searchsorted(s_out, s_b, side="right" if forward else "left"))
            segs.append((j, t_b, dv))
        segs.append((t_out.size, float(t_out[-1]), None))
        return segs

    def _check_times(self, t0: Any, times: Any) -> tuple[float, np.ndarray]:
        return check_output_times(self._label(), t0, times)

    def _check_states(self, states: Any) -> np.ndarray:
        try:
            arr = np.array(states, dtype=float)
        except (TypeError, ValueError) as exc:
            raise StateError(f"{self._label()}: states must be a numeric (N, 6) array: {exc}") from None
        if arr.ndim == 1:
            arr = arr.reshape(1, -1)
        if arr.ndim != 2 or arr.shape[1] != 6:
            raise StateError(f"{self._label()}: states must have shape (N, 6), got {np.shape(states)}")
        if not np.all(np.isfinite(arr)):
            raise StateError(f"{self._label()}: {int(np.sum(~np.all(np.isfinite(arr), axis=1)))} state(s) "
                             "contain NaN or inf")
        return arr

    # -- propagation --------------------------------------------------------------------------------
    def propagate(self, states: np.ndarray, t0: float, times: Any, **options: Any) -> Propagation:
        """Propagate ``states`` (N, 6) from ``t0`` to each of ``times`` (scalar or (K,) TU,
        monotonic in one direction) through the burns, segment by segment; ``options`` (the
        base's keywords, e.g. ``rtol``) go to every base call. Without a burn on the way this is
        the base's own call, bit for bit (with its ``steps``)."""
        t0, t_out = self._check_times(t0, times)
        if not self._crossed(t0, float(t_out[-1])):
            return self.base.propagate(states, t0, times, **options)
        options.pop("steps", None)  # carried step sizes do not survive a burn
        cur = self._check_states(states)
        n = cur.shape[0]
        out = np.empty((t_out.size, n, 6))
        alive = np.ones(n, dtype=bool)
        body = np.full(n, -1, dtype=np.int64)
        t_hit = np.full(n, np.inf)
        t_cur, k = t0, 0
        for j, t_end, dv in self._segments(t0, t_out):
            ts = _with_end(t_out[k:j], t_end)
            seg = self._segment(cur, t_cur, ts, (alive, body, t_hit), options)
            out[k:j] = seg[: j - k]
            cur = seg[-1].copy()
            if dv is not None:
                cur[alive, 3:] += dv
            t_cur, k = t_end, j
        return Propagation(times=t_out, states=out, alive=alive, impact_body=body, impact_time=t_hit)

    def _segment(self, cur: np.ndarray, t_cur: float, ts: np.ndarray, fate: tuple, options: dict) -> np.ndarray:
        """States (len(ts), N, 6) of the living particles of ``cur`` flown by the base from
        ``t_cur`` to ``ts``; the dead ones stay where they are. ``fate`` (alive, impact body,
        impact time) is updated for the particles that hit a body here."""
        alive, body, t_hit = fate
        res = np.repeat(cur[None], ts.size, axis=0)
        same = int(np.sum(ts == t_cur))  # leading outputs at the segment's start: its start state
        live = np.flatnonzero(alive)
        if ts.size > same and live.size:
            prop = self.base.propagate(cur[live], t_cur, ts[same:], **options)
            res[same:, live] = prop.states
            died = ~np.asarray(prop.alive, dtype=bool)
            body[live[died]] = np.asarray(prop.impact_body)[died]
            t_hit[live[died]] = np.asarray(prop.impact_time)[died]
            alive[live[died]] = False
        return res

    def propagate_with_stm(self, state: np.ndarray, t0: float, times: Any) -> tuple[np.ndarray, np.ndarray]:
        """One ``state`` (6,) and its state transition matrix from ``t0`` to each of ``times``:
        the base's, chained across the burns (identity jump). Raises ``StateError`` for malformed
        input and the base's ``PropagationError`` when the trajectory hits a body."""
        x, t0, t_out = check_stm_request(self._label(), state, t0, times)
        if not self._crossed(t0, float(t_out[-1])):
            return self.base.propagate_with_stm(x, t0, t_out)
        out_x, out_phi, _ = self._chained(x, t0, t_out, None)
        return out_x, out_phi

    @property
    def sensitivity_parameters(self) -> tuple[str, ...]:
        """The base's parameters whose d x / d p :meth:`propagate_with_sensitivity` integrates."""
        return tuple(getattr(self.base, "sensitivity_parameters", ()))

    def propagate_with_sensitivity(self, state: np.ndarray, t0: float, times: Any,
                                   name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`propagate_with_stm`, and d x / d p (K, 6) of the base's parameter ``name``
        chained across the burns: s(t) = Phi(t, t_j) s(t_j) + s_j(t) on each segment (the delta-v
        does not depend on the parameter). Raises ``StateError`` when the base has no such
        sensitivity."""
        x, t0, t_out = check_stm_request(self._label(), state, t0, times)
        if name not in self.sensitivity_parameters:
            raise StateError(f"{self._label()}: the base model gives no sensitivity of {name!r}")
        if not self._crossed(t0, float(t_out[-1])):
            return self.base.propagate_with_sensitivity(x, t0, t_out, name)
        return self._chained(x, t0, t_out, name)

    def _chained(self, x: np.ndarray, t0: float, t_out: np.ndarray,
                 name: str | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """States, STMs and (with a parameter ``name``) sensitivities at ``t_out``, segment by
        segment between the burns."""
        out_x = np.empty((t_out.size, 6))
        out_phi = np.empty((t_out.size, 6, 6))
        out_s = None if name is None else np.empty((t_out.size, 6))
        phi, sens = np.eye(6), np.zeros(6)
        t_cur, k = t0, 0
        for j, t_end, dv in self._segments(t0, t_out):
            ts = _with_end(t_out[k:j], t_end)
            xs, stms, ss = self._stm_segment(x, t_cur, ts, name)
            out_x[k:j] = xs[: j - k]
            out_phi[k:j] = stms[: j - k] @ phi
            if out_s is not None:
                out_s[k:j] = stms[: j - k] @ sens + ss[: j - k]
                sens = stms[-1] @ sens + ss[-1]
            x, phi = xs[-1].copy(), stms[-1] @ phi
            if dv is not None:
                x = x.copy()
                x[3:] += dv
            t_cur, k = t_end, j
        return out_x, out_phi, out_s

    def _stm_segment(self, x: np.ndarray, t_cur: float, ts: np.ndarray,
                     name: str | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        xs = np.repeat(x[None], ts.size, axis=0)
        stms = np.repeat(np.eye(6)[None], ts.size, axis=0)
        ss = np.zeros((ts.size, 6))
        same = int(np.sum(ts == t_cur))
        if ts.size > same:
            if name is None:
                xs[same:], stms[same:] = self.base.propagate_with_stm(x, t_cur, ts[same:])
            else:
                xs[same:], stms[same:], ss[same:] = self.base.propagate_with_sensitivity(x, t_cur, ts[same:], name)
        return xs, stms, ss

    @property
    def dense_trajectory(self):
        """``dense_trajectory(state (6,), t0, t1, **options)``: one state flown over ``[t0, t1]``
        through the burns, kept as an :class:`ImpulsiveTrajectory` (the base's own
        ``DenseTrajectory`` when no burn lies on the way). Present only when the base has it."""
        if not callable(getattr(self.base, "dense_trajectory", None)):
            raise AttributeError(f"{self._label()}: the base model has no dense_trajectory")
        return self._dense_trajectory

    def _dense_trajectory(self, state: np.ndarray, t0: float, t1: float, **options: Any) -> Any:
        arr = self._check_states(state)
        if arr.shape[0] != 1:
            raise StateError(f"{self._label()}: dense_trajectory takes one state (6,), got {arr.shape[0]}")
        t0, t_out = self._check_times(t0, t1)
        crossed = self._crossed(t0, float(t_out[-1]))
        if not crossed:
            return self.base.dense_trajectory(arr[0], t0, float(t_out[-1]), **options)
        x, t_cur = arr[0], t0
        pieces: list[Any] = []
        for t_b, dv in crossed:
            pieces.append(self._piece(x, t_cur, t_b, options))
            if not pieces[-1].alive:
                break
            x, t_cur = pieces[-1].states(t_b)[0].copy(), t_b
            x[3:] += dv
        else:
            pieces.append(self._piece(x, t_cur, float(t_out[-1]), options))
        return ImpulsiveTrajectory(t0, [t for t, _ in crossed[: len(pieces) - 1]], pieces)

    def _piece(self, x: np.ndarray, t_start: float, t_end: float, options: dict) -> Any:
        if t_start == t_end:
            return _Frozen(x, t_start)
        return self.base.dense_trajectory(x, t_start, t_end, **options)

    # -- solve-for parameters --------------------------------------------------------------------
    @property
    def solve_for_parameters(self) -> tuple[str, ...]:
        """The base's solve-for parameters, then ``delta_v_{k}_{x,y,z}_ms`` for every impulse."""
        own = tuple(n for k in range(len(self.impulses)) for n in delta_v_parameter_names(k))
        return tuple(getattr(self.base, "solve_for_parameters", ())) + own

    def impulse_axis(self, name: str) -> tuple[int, int] | None:
        """(impulse index into :attr:`impulses`, axis 0-2) of a ``delta_v_{k}_{axis}_ms`` name of
        this model, else None."""
        parts = name.split("_")
        if (len(parts) != 5 or parts[:2] != ["delta", "v"] or parts[4] != "ms" or parts[3] not in _AXES
                or not parts[2].isdigit()):
            return None
        k = int(parts[2])
        if k >= len(self.impulses) or name != delta_v_parameter_names(k)[_AXES.index(parts[3])]:
            return None
        return k, _AXES.index(parts[3])

    def _unknown(self, name: str) -> StateError:
        return StateError(f"{self._label()}: no solve-for parameter {name!r}; known: "
                          + (", ".join(self.solve_for_parameters) or "none"))

    def parameter(self, name: str) -> float:
        """The value of solve-for parameter ``name``: an impulse's synodic component in m/s, or
        the base's parameter."""
        ka = self.impulse_axis(name)
        if ka is not None:
            return float(self.impulses[ka[0]].dv[ka[1]] * MS_PER_VU)
        if name in tuple(getattr(self.base, "solve_for_parameters", ())):
            return float(self.base.parameter(name))
        raise self._unknown(name)

    def with_parameters(self, **values: float) -> "ImpulsiveDynamics":
        """A new ImpulsiveDynamics with these solve-for values (impulse components in m/s; the
        base's parameters through ``base.with_parameters``); this one is unchanged."""
        base_names = tuple(getattr(self.base, "solve_for_parameters", ()))
        dvs = [imp.dv.copy() for imp in self.impulses]
        for_base = {}
        for name, v in values.items():
            ka = self.impulse_axis(name)
            if ka is None and name not in base_names:
                raise self._unknown(name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not np.isfinite(v):
                raise StateError(f"{self._label()}: solve-for parameter {name!r} = {v!r} must be a finite number")
            if ka is None:
                for_base[name] = v
            else:
                dvs[ka[0]][ka[1]] = float(v) / MS_PER_VU
        base = self.base.with_parameters(**for_base) if for_base else self.base
        return ImpulsiveDynamics(base, [Impulse(imp.t, dv, imp.label) for imp, dv in zip(self.impulses, dvs)])


def _with_end(ts: np.ndarray, t_end: float) -> np.ndarray:
    """``ts`` with ``t_end`` appended unless it is already the last: a segment's flight must
    reach its end (the burn) whatever outputs it has."""
    return ts if ts.size and ts[-1] == t_end else np.append(ts, t_end)


class _Frozen:
    """A zero-length piece (a burn at the span's start): the one state at the one time."""

    def __init__(self, x: np.ndarray, t: float) -> None:
        self.x, self.t0, self.t1 = np.array(x, dtype=float), float(t), float(t)
        self.alive, self.impact_body, self.impact_time = True, -1, np.inf

    def states(self, times) -> np.ndarray:
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        return np.repeat(self.x[None], ts.size, axis=0)


class ImpulsiveTrajectory:
    """A trajectory through burns, evaluated at any time of its span: one dense piece per
    segment (each the base's ``DenseTrajectory``), with the API of
    :class:`~cistrack.propagation.dense.DenseTrajectory` that a run uses.

    Attributes
    ----------
    t0, t1 : float        start and end of the span, TU (``t1``: the impact time after a hit)
    burn_times : (P-1,)   the burns between the pieces, TU, in the order flown
    pieces : list         the P pieces, in the order flown
    alive, impact_body, impact_time : as the last piece's
    """

    def __init__(self, t0: float, burn_times: list[float], pieces: list[Any]) -> None:
        self.t0 = float(t0)
        self.burn_times = np.asarray(burn_times, dtype=float)
        self.pieces = list(pieces)
        last = self.pieces[-1]
        self.t1 = float(last.t1)
        self.alive, self.impact_body, self.impact_time = bool(last.alive), int(last.impact_body), float(last.impact_time)
        self._forward = self.t1 >= self.t0

    def covers(self, times) -> bool:
        """Whether every one of ``times`` (TU) lies inside the span."""
        ts = np.atleast_1d(np.asarray(times, dtype=float))
        lo, hi = min(self.t0, self.t1), max(self.t0, self.t1)
        return bool(np.all((ts >= lo) & (ts <= hi)))

    def states(self, times) -> np.ndarray:
        """States (K, 6) at ``times`` (scalar or (K,) TU inside the span); at a burn's time the
        pre-burn state."""
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        if not self.covers(ts):
            raise StateError(f"trajectory over [{self.t0:g}, {self.t1:g}] TU asked for times outside it "
                             f"(from {ts.min():g} to {ts.max():g})")
        sign = 1.0 if self._forward else -1.0
        which = np.searchsorted(sign * self.burn_times, sign * ts, side="left" if self._forward else "right")
        out = np.empty((ts.size, 6))
        for p in np.unique(which):
            sel = which == p
            out[sel] = self.pieces[int(p)].states(ts[sel])
        return out


def fly_plan(plan: ManeuverPlan | None, dynamics: Dynamics, x0: np.ndarray, t0: float, t_end: float,
             say: Any = None, where: str = "maneuver plan", who: str | None = None) -> tuple[Dynamics, list[Impulse]]:
    """The truth model that flies ``plan``'s burns from ``x0`` (6,) at ``t0`` over ``(t0, t_end]``
    (TU), and the impulses: ``dynamics`` wrapped in :class:`ImpulsiveDynamics`, or ``dynamics``
    itself (and no impulse) when there is no plan or it makes no burn there. ``say`` (a callable)
    gets one line per burn (:func:`describe_impulse`) and per burn of the plan outside the span;
    without ``say`` (a run under --quiet) the latter is a warning (logger ``cistrack.maneuvers``). Raises
    ConfigError, prefixed by ``where``, when the plan fails or returns anything but impulses
    inside the span; a plan that raises its own exception (a burn with a NaN or 4-component dv, say) is named by ``who`` (default: its
    kind and registered name; the pipeline adds its distribution)."""
    if plan is None:
        return dynamics, []
    try:
        impulses = _planned(plan, dynamics, (x0, t0, t_end), who or f"maneuver-plan '{component_name(plan)}'")
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    flown = ImpulsiveDynamics(dynamics, impulses) if impulses else dynamics
    impulses = list(flown.impulses) if impulses else []
    for line in burn_lines(impulses):
        (say or (lambda text: None))(line)
    days = float(units.tu_to_days(t_end - t0))
    for text in plan.burns_outside(float(t0), float(t_end)):  # part of the user's plan is dropped: said always
        line = f"{where}: outside the run (0 to {days:g} days), not flown: {text}"
        say(line) if say is not None else logging.getLogger("cistrack.maneuvers").warning(f"warning: {line}")
    if not impulses and say is not None:
        say(f"{where}: no burn inside the run ({days:g} days); the truth is ballistic")
    return flown, impulses


def _planned(plan: ManeuverPlan, dynamics: Dynamics, start: tuple, who: str) -> list[Impulse]:
    """``plan.impulses(dynamics, x0, t0, t_end)`` (``start``: x0 (6,), t0, t_end TU), each an
    Impulse inside ``(t0, t_end]``; ConfigError naming the plan ``who`` otherwise."""
    x0, t0, t_end = start
    try:
        got = plan.impulses(dynamics, np.asarray(x0, dtype=float).reshape(6), float(t0), float(t_end))
    except CistrackError:
        raise
    except BaseException as exc:  # the plugin's own bug: named, never a traceback
        if not plugin_fault(exc):
            raise
        raise ConfigError(f"{who}: impulses() raised {exception_text(exc)}") from exc
    if not isinstance(got, (list, tuple)):
        raise ConfigError(f"{who}: impulses() returned {type(got).__name__}, not a list of Impulse")
    for imp in got:
        if not isinstance(imp, Impulse):
            raise ConfigError(f"{who}: impulses() returned a {type(imp).__name__} among its burns, not an Impulse")
        if not t0 < imp.t <= t_end:
            raise ConfigError(f"{who}: impulse {imp.label!r} at t = {units.tu_to_days(imp.t):.6g} days lies outside "
                              f"the run's span ({units.tu_to_days(t0):g}, {units.tu_to_days(t_end):.6g}] days")
    return list(got)


BURN_LINES = 5
"""Most burns a run's log describes one line each; more are summarised in one line (a plan of
1,000 burns had written 1,000 lines before the run and 1,000 in its summary)."""


def burn_lines(impulses: Sequence[Impulse]) -> list[str]:
    """The log's lines on the truth's burns: one each (:func:`describe_impulse`) up to
    :data:`BURN_LINES`, else one line with their count, time span and sizes."""
    if len(impulses) <= BURN_LINES:
        return [describe_impulse(imp, k) for k, imp in enumerate(impulses, 1)]
    days = [float(units.tu_to_days(imp.t)) for imp in impulses]
    sizes = [float(np.linalg.norm(imp.dv)) * MS_PER_VU for imp in impulses]
    return [burns_summary(days, sizes)]


def burns_summary(days: Sequence[float], sizes_ms: Sequence[float]) -> str:
    """One line on many truth burns at ``days`` (since the epoch) of ``sizes_ms`` (m/s)."""
    return (f"truth burns: {len(days):,} from {min(days):.4f} to {max(days):.4f} days, {min(sizes_ms):.4g} to "
            f"{max(sizes_ms):.4g} m/s each, {sum(sizes_ms):.4g} m/s in all (one line each for up to {BURN_LINES})")


def describe_impulse(impulse: Impulse, k: int) -> str:
    """One line on impulse ``k`` (1-based) for a run's log: time in days, size in m/s, its label
    and its synodic direction."""
    size = float(np.linalg.norm(impulse.dv))
    label = f", {impulse.label}" if impulse.label else ""
    head = f"truth burn {k} at {float(units.tu_to_days(impulse.t)):.4f} days: |dv| = {size * MS_PER_VU:.4g} m/s{label}"
    if size == 0:
        return f"{head}; a zero burn, not flown"
    unit = impulse.dv / size
    return f"{head}; synodic direction ({unit[0]:+.3f}, {unit[1]:+.3f}, {unit[2]:+.3f})"
