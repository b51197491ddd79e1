"""State transition matrices by central finite differences of ``Dynamics.propagate``.

The generic default behind :meth:`cistrack.interfaces.dynamics.Dynamics.propagate_with_stm`:
the nominal state and twelve perturbed copies (one plus and one minus step per coordinate) are
propagated in one call, and column j of the STM is the central difference

    Phi[:, j](t) = (phi(x + h_j e_j, t) - phi(x - h_j e_j, t)) / (2 h_j).

The error is O(h^2) from the flow's curvature plus O(tol / h) from the integrator's adaptive
steps; the default steps (1e-6 LU = 0.38 km, 1e-6 VU = 1 mm/s) keep both near 1e-6 relative for
cislunar orbits at the built-in tolerances (1e-12). Models with variational equations override
the method.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.errors import PropagationError, StateError

__all__ = ["DEFAULT_STM_STEPS", "check_stm_request", "stm_by_central_differences"]

DEFAULT_STM_STEPS: np.ndarray = np.array([1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6])
"""Central-difference steps per coordinate: position LU, velocity VU."""


def check_stm_request(label: str, state: Any, t0: Any, times: Any) -> tuple[np.ndarray, float, np.ndarray]:
    """Validated ``(state (6,), t0, times (K,))``; raises :class:`StateError` naming what is wrong.

    ``times`` must be finite, non-empty and monotonic in one direction from ``t0`` (as for
    ``propagate``)."""
    try:
        x = np.asarray(state, dtype=float).reshape(-1)
        t_out = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        t0 = float(t0)
    except (TypeError, ValueError) as exc:
        raise StateError(f"{label}: propagate_with_stm needs a numeric state (6,), t0 and times: {exc}") from None
    if x.shape != (6,):
        raise StateError(f"{label}: propagate_with_stm takes one state of shape (6,), got {np.shape(state)}")
    if not np.all(np.isfinite(x)):
        raise StateError(f"{label}: propagate_with_stm: the state contains NaN or inf: {x}")
    if t_out.size == 0:
        raise StateError(f"{label}: propagate_with_stm: no output times given")
    if not (np.isfinite(t0) and np.all(np.isfinite(t_out))):
        raise StateError(f"{label}: propagate_with_stm: t0 and times must be finite")
    d = np.diff(np.concatenate(([t0], t_out)))
    if not (np.all(d >= 0) or np.all(d <= 0)):
        raise StateError(f"{label}: propagate_with_stm: times must be monotonic in one direction "
                         f"from t0={t0}")
    return x, t0, t_out


def stm_by_central_differences(dynamics: Any, state: Any, t0: float, times: Any,
                               steps: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) and STMs (K, 6, 6) of ``state`` (6,) from ``t0`` to ``times`` (K,) TU.

    ``dynamics``: a :class:`cistrack.interfaces.dynamics.Dynamics` (only its ``propagate`` is used).

    ``steps`` (6,): the difference step per coordinate (LU, VU), default
    :data:`DEFAULT_STM_STEPS`. The states are those of the nominal particle of the same call.
    Raises :class:`PropagationError` if the nominal or a perturbed trajectory hits a body.
    """
    label = getattr(dynamics, "_label", lambda: type(dynamics).__name__)()
    x, t0, t_out = check_stm_request(label, state, t0, times)
    h = DEFAULT_STM_STEPS if steps is None else np.asarray(steps, dtype=float).reshape(6)
    if not np.all(np.isfinite(h) & (h > 0)):
        raise StateError(f"{label}: finite-difference steps must be 6 positive numbers, got {steps!r}")
    batch = np.repeat(x[None], 13, axis=0)
    for j in range(6):
        batch[1 + 2 * j, j] += h[j]
        batch[2 + 2 * j, j] -= h[j]
    prop = dynamics.propagate(batch, t0, t_out)
    if not np.all(prop.alive):
        bodies = getattr(dynamics, "bodies", ())
        i = int(np.argmin(prop.alive))
        b = int(prop.impact_body[i])
        name = bodies[b].name if 0 <= b < len(bodies) else f"body {b}"
        raise PropagationError(f"{label}: the trajectory (or a perturbed copy for the state transition "
                               f"matrix) hits the {name} at t={float(prop.impact_time[i]):.6g} TU")
    s = prop.states                                            # (K, 13, 6)
    stm = (s[:, 1::2, :] - s[:, 2::2, :]) / (2.0 * h[None, :, None])  # (K, j, i)
    return s[:, 0, :].copy(), np.ascontiguousarray(np.transpose(stm, (0, 2, 1)))
