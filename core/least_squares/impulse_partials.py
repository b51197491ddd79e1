"""Partials of the propagated states with respect to impulsive burns' delta-v, from the state
transition matrices the fit computes anyway.

A burn at ``t_b`` adds ``dv`` to the velocity (:class:`~cistrack.propagation.impulses.ImpulsiveDynamics`,
whose jump Jacobian is the identity), so with the state held at the fit epoch ``t0``

- forward (``t0 <= t_b``): d x(t) / d dv = Phi(t, t_b) [0; I] for ``t > t_b``, zero before;
- backward (``t_b < t0``): d x(t) / d dv = -Phi(t, t_b) [0; I] for ``t <= t_b`` (the state at
  ``t_b`` is the pre-burn one, reached by subtracting ``dv``), zero after;

and Phi(t, t_b) = Phi(t, t0) Phi(t_b, t0)^-1. One propagation of the state and its transition
matrix, the burn times among its outputs, gives every burn's three columns: the central
differences of :mod:`cistrack.least_squares.solve_for_parameters` took six more propagations of
the orbit per burn and Jacobian (compared in ``tests/least_squares/test_impulse_partials.py``).
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cistrack.interfaces.dynamics import Dynamics
from cistrack.propagation.impulses import MS_PER_VU, ImpulsiveDynamics

__all__ = ["impulse_columns", "delta_v_state_partials"]


def impulse_columns(dynamics: Dynamics, names: Sequence[str]) -> dict[int, tuple[float, int]]:
    """{index into ``names``: (burn time TU, velocity axis 0-2)} for the names that are delta-v
    components of ``dynamics`` (an ImpulsiveDynamics); empty for any other model."""
    if not isinstance(dynamics, ImpulsiveDynamics):
        return {}
    out = {}
    for j, name in enumerate(names):
        ka = dynamics.impulse_axis(name)
        if ka is not None:
            out[j] = (float(dynamics.impulses[ka[0]].t), ka[1])
    return out


def delta_v_state_partials(times: np.ndarray, t0: float, stms: np.ndarray, burn_stms: dict[float, np.ndarray],
                           columns: dict[int, tuple[float, int]]) -> np.ndarray:
    """d x(t_k) / d p (K, 6, J) for the J ``columns`` (in their key order), p a delta-v component
    in m/s, x in LU and VU.

    ``times`` (K,) TU; ``stms`` (K, 6, 6) Phi(t_k, t0); ``burn_stms`` {burn time: Phi(t_b, t0)}."""
    t = np.asarray(times, dtype=float)
    out = np.zeros((t.size, 6, len(columns)))
    for c, (tb, axis) in enumerate(columns.values()):
        g = np.linalg.solve(burn_stms[tb], np.eye(6)[:, 3 + axis])   # Phi(t0, t_b) [0; e_axis]
        if tb >= t0:
            side, sign = t > tb, 1.0
        else:
            side, sign = t <= tb, -1.0
        out[side, :, c] = sign * (stms[side] @ g) / MS_PER_VU
    return out
