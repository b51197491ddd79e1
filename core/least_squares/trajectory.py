"""The fitted trajectory over an arc: states (and transition matrices) at measurement times.

The fit's epoch ``t0`` may lie anywhere in the arc: times before it are propagated backward and
times after it forward (the dynamics' ``propagate`` takes one direction per call); repeated
times (several sites at once) are propagated once.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import PropagationError
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["arc_states", "arc_states_and_stms", "arc_states_stms_and_sensitivity", "ensemble_arc_states"]


def _sides(t0: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Distinct times, the index of each time among them, and the distinct times split into
    (at t0, after t0 increasing, before t0 decreasing)."""
    uniq, inv = np.unique(times, return_inverse=True)
    return uniq, inv, [uniq[uniq == t0], uniq[uniq > t0], uniq[uniq < t0][::-1]]


def _label(dynamics: Dynamics) -> str:
    return getattr(dynamics, "_label", lambda: type(dynamics).__name__)()


def arc_states(dynamics: Dynamics, state: np.ndarray, t0: float, times: np.ndarray) -> np.ndarray:
    """States (K, 6) [LU, VU] of ``state`` (6,) at ``t0`` propagated to ``times`` (K,) TU.

    Raises :class:`cistrack.errors.PropagationError` naming the body when the trajectory hits one.
    """
    uniq, inv, (at, after, before) = _sides(t0, times)
    out = {}
    x = np.asarray(state, dtype=float).reshape(1, 6)
    for t in at:
        out[float(t)] = x[0]
    for side in (after, before):
        if side.size == 0:
            continue
        prop = dynamics.propagate(x, t0, side)
        if not bool(np.all(prop.alive)):
            b = int(prop.impact_body[0])
            bodies = dynamics.bodies
            name = bodies[b].name if 0 <= b < len(bodies) else f"body {b}"
            raise PropagationError(f"{_label(dynamics)}: the fitted trajectory hits the {name} at "
                                   f"t={float(prop.impact_time[0]):.6g} TU, inside the arc "
                                   f"[{times.min():.6g}, {times.max():.6g}] TU")
        for k, t in enumerate(side):
            out[float(t)] = prop.states[k, 0]
    per_time = np.array([out[float(t)] for t in uniq])
    return per_time[inv]


def ensemble_arc_states(dynamics: Dynamics, states: np.ndarray, t0: float,
                        times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States (K, N, 6) [LU, VU] of ``states`` (N, 6) at ``t0`` propagated together to ``times``
    (K,) TU (one propagation each side of ``t0``), and (N,) bool: the orbits that hit no body
    over the times (the others' states are the dynamics' after the impact; leave them out)."""
    uniq, inv, (at, after, before) = _sides(t0, times)
    x = np.asarray(states, dtype=float).reshape(-1, 6)
    per_time = np.empty((uniq.size, x.shape[0], 6))
    alive = np.ones(x.shape[0], dtype=bool)
    per_time[np.isin(uniq, at)] = x
    for side in (after, before):
        if side.size == 0:
            continue
        prop = dynamics.propagate(x, t0, side)
        alive &= np.asarray(prop.alive, dtype=bool).reshape(-1)
        per_time[np.searchsorted(uniq, side)] = prop.states
    return per_time[inv], alive


def arc_states_and_stms(dynamics: Dynamics, state: np.ndarray, t0: float,
                        times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) and transition matrices (K, 6, 6) d x(t_k) / d x(t0) over ``times`` (K,) TU,
    from the dynamics' ``propagate_with_stm`` (variational equations where the model has them)."""
    return _arc_variational(dynamics, state, t0, times, dynamics.propagate_with_stm)[:2]


def arc_states_stms_and_sensitivity(dynamics: Dynamics, state: np.ndarray, t0: float, times: np.ndarray,
                                    name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`arc_states_and_stms`, and d x(t_k) / d p (K, 6) of the model's parameter ``name``
    (the state at ``t0`` held), from its ``propagate_with_sensitivity``."""
    return _arc_variational(dynamics, state, t0, times,
                            lambda x, t, side: dynamics.propagate_with_sensitivity(x, t, side, name))


def _arc_variational(dynamics: Dynamics, state: np.ndarray, t0: float, times: np.ndarray,
                     propagate) -> tuple[np.ndarray, ...]:
    """States (K, 6), transition matrices (K, 6, 6) and, where ``propagate`` gives them,
    sensitivities (K, 6) over ``times``: each side of ``t0`` one call of ``propagate(x, t0, side)``."""
    uniq, inv, (at, after, before) = _sides(t0, times)
    got: dict[float, tuple[np.ndarray, ...]] = {}
    x = np.asarray(state, dtype=float).reshape(6)
    for t in at:
        got[float(t)] = (x, np.eye(6), np.zeros(6))
    for side in (after, before):
        if side.size == 0:
            continue
        out = [np.asarray(a, dtype=float) for a in propagate(x, t0, side)]
        s, phi = out[0], out[1]
        if s.shape != (side.size, 6) or phi.shape != (side.size, 6, 6):
            raise PropagationError(f"{_label(dynamics)}: propagate_with_stm returned shapes {s.shape} and "
                                   f"{phi.shape} for {side.size} times; expected (K, 6) and (K, 6, 6)")
        for k, t in enumerate(side):
            got[float(t)] = tuple(a[k] for a in out) + ((np.zeros(6),) if len(out) == 2 else ())
    arrays = [np.array([got[float(t)][i] for t in uniq]) for i in range(3)]
    if not all(np.all(np.isfinite(a)) for a in arrays):
        raise PropagationError(f"{_label(dynamics)}: the state or its transition matrix is not finite "
                               "over the arc")
    return tuple(a[inv] for a in arrays)
