"""State and state transition matrix together: the variational equations on the compiled DOP853.

A model that can write its variational equations supplies a module-level ``@njit`` function
``stm_rhs(t, y, params, out)`` on 42 components: y[0:6] the state (as its ``rhs``), y[6:42] the
6x6 STM Phi row-major, with out[6:42] = (A(t, x) Phi) row-major, A = d rhs / d x. The generated
integrator (:func:`cistrack.propagation.kernels.kernels_for` with ``dim = 42``) integrates the
augmented system with per-step error control over all 42 components; impacts on the model's
bodies are located as in :meth:`CompiledDynamics.propagate` (on y[0:3]).

Used by the built-in models' ``propagate_with_stm`` (the interface's optional method), in the
frame their kernels integrate in.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.errors import PropagationError, StateError
from cistrack.interfaces.transition_matrix import check_stm_request
from cistrack.propagation.compiled import CompiledDynamics
from cistrack.propagation.kernels import kernels_for

__all__ = ["propagate_variational", "propagate_variational_with", "STM_DIM"]

STM_DIM = 42
"""Length of the augmented state: 6 state components and the 36 entries of the STM."""


def propagate_variational(dynamics: CompiledDynamics, stm_rhs: Any, state: Any, t0: float, times: Any, *,
                          rtol: float | None = None, atol: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """States (K, 6) and STMs (K, 6, 6) of one ``state`` (6,) from ``t0`` to ``times`` (K,) TU.

    ``stm_rhs``: the model's 42-component variational right-hand side (module docstring), in the
    frame of the model's kernel; ``state`` is in that frame too. Tolerances default to the
    model's. Raises :class:`StateError` for malformed input and :class:`PropagationError` when
    the trajectory hits a body, reaches the step limit or its step size underflows.
    """
    states, stms, _ = propagate_variational_with(dynamics, stm_rhs, state, t0, times, 0, rtol=rtol, atol=atol)
    return states, stms


def propagate_variational_with(dynamics: CompiledDynamics, stm_rhs: Any, state: Any, t0: float, times: Any,
                               extra: int, *, rtol: float | None = None,
                               atol: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`propagate_variational`, with ``extra`` more components after the STM, zero at
    ``t0`` (a parameter's sensitivity d x / d p: ``stm_rhs`` on 42 + ``extra`` components writes
    their derivatives) -> (states (K, 6), STMs (K, 6, 6), extras (K, extra))."""
    label = dynamics._label()
    x, t0, t_out = check_stm_request(label, state, t0, times)
    if stm_rhs is None or not hasattr(stm_rhs, "py_func"):
        raise StateError(f"{label}: the variational right-hand side must be a numba @njit function")
    dim = STM_DIM + int(extra)
    y0 = np.concatenate([x, np.eye(6).reshape(-1), np.zeros(int(extra))])[None]
    out = np.empty((t_out.size, 1, dim))
    impact_body = np.full(1, -1, dtype=np.int64)
    impact_time = np.full(1, np.inf)
    status = np.zeros(1, dtype=np.int64)
    pos, rad = dynamics._bodies_arrays()
    mod = kernels_for(stm_rhs, dim, type(dynamics).body_motion)
    mod.propagate_kernel(0, 1, np.ascontiguousarray(y0), dynamics._params(), t0, np.ascontiguousarray(t_out),
                         float(dynamics.rtol if rtol is None else rtol),
                         float(dynamics.atol if atol is None else atol), pos, rad,
                         int(dynamics.max_steps), np.zeros(1), out, impact_body, impact_time, status)
    _check_status(dynamics, label, status, impact_body, impact_time, t_out)
    y = out[:, 0, :]
    return y[:, :6].copy(), y[:, 6:STM_DIM].reshape(-1, 6, 6).copy(), y[:, STM_DIM:].copy()


def _check_status(dynamics: CompiledDynamics, label: str, status: np.ndarray, impact_body: np.ndarray,
                  impact_time: np.ndarray, t_out: np.ndarray) -> None:
    """PropagationError when the kernel stopped short (step limit, step-size underflow, impact)."""
    if status[0] >= 2:
        why = "the step limit max_steps" if status[0] == 2 else "a step-size underflow"
        raise PropagationError(f"{label}: the state and its transition matrix did not reach t={t_out[-1]:g} TU "
                               f"({why})")
    if impact_body[0] >= 0:
        bodies = dynamics.bodies
        b = int(impact_body[0])
        name = bodies[b].name if b < len(bodies) else f"body {b}"
        raise PropagationError(f"{label}: the trajectory hits the {name} at t={float(impact_time[0]):.6g} TU; "
                               "no state transition matrix beyond an impact")
