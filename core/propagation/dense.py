"""Dense output: one particle's trajectory over a whole span, evaluated at any time inside it.

:meth:`CompiledDynamics.dense_trajectory <cistrack.propagation.CompiledDynamics.dense_trajectory>`
integrates once with the per-particle DOP853 and keeps each step's 7th-order interpolant (the
Dormand-Prince continuous extension, three extra right-hand-side evaluations per step); a
:class:`DenseTrajectory` then gives the state at any time of the span without integrating again.
Between steps the interpolant's error is of the order of the integrator's local error (measured
on the 9:2 NRHO at the default tolerance: below 1e-11 LU against a scipy rtol 1e-13 solution;
tests/propagation/test_dense_output.py).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import NamedTuple

import numpy as np

from cistrack.errors import PropagationError, StateError

from cistrack.propagation.dop853_dense_source import CTL_SIZE
from cistrack.propagation.dop853_tableau import INTERPOLATOR_POWER

__all__ = ["DenseTrajectory", "DenseSteps", "KernelInputs", "integrate_dense"]


class DenseSteps(NamedTuple):
    """The step records of a dense integration, one entry per step (S steps, state size dim)."""

    start: np.ndarray
    """(S,) start time of each step, TU."""
    size: np.ndarray
    """(S,) signed size of each step, TU."""
    state: np.ndarray
    """(S, dim) state at each step's start."""
    coefficients: np.ndarray
    """(S, 7, dim) the interpolant's coefficients F0..F6 per step."""


@dataclass(frozen=True)
class KernelInputs:
    """What a generated integrator kernel takes besides the state and the times."""

    params: np.ndarray
    """(P,) the model's parameters, as its right-hand side reads them."""
    rtol: float
    atol: float
    body_pos: np.ndarray
    """(B, 5) impact bodies: position and bounds on speed and acceleration (see
    ``CompiledDynamics._bodies_arrays``)."""
    body_rad: np.ndarray
    """(B,) their radii, LU."""
    max_steps: int


class DenseTrajectory:
    """A propagated trajectory that can be evaluated at any time of its span.

    Attributes
    ----------
    t0, t1 : float         start and end of the span, TU (``t1`` is the impact time if the
                           particle hit a body; ``t1 < t0`` for a backward span)
    step_start : (S,) float   start time of each step, TU
    step_size : (S,) float    signed size of each step, TU
    step_state : (S, dim)     state at each step's start
    coefficients : (S, 7, dim)  the interpolant's coefficients F0..F6 per step
    impact_body : int      index into the model's ``bodies`` of the body hit, -1 for none
    impact_time : float    TU of the impact, +inf for none
    transform : callable or None
        ``transform(states (K, dim), times (K,)) -> (K, dim)`` applied to evaluated states (a
        model integrating in another frame converts back to its public one here).
    """

    def __init__(self, t0: float, t1: float, steps: DenseSteps, end_state: np.ndarray,
                 impact_body: int = -1, impact_time: float = np.inf,
                 transform: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None) -> None:
        self.t0, self.t1 = float(t0), float(t1)
        self.step_start, self.step_size = steps.start, steps.size
        self.step_state, self.coefficients = steps.state, steps.coefficients
        self.end_state = end_state
        self.impact_body, self.impact_time = int(impact_body), float(impact_time)
        self.transform = transform
        self._direction = 1.0 if t1 >= t0 else -1.0

    @property
    def alive(self) -> bool:
        """False if the particle hit a body inside the span."""
        return self.impact_body < 0

    def covers(self, times) -> bool:
        """Whether every one of ``times`` (TU) lies inside the span."""
        ts = np.atleast_1d(np.asarray(times, dtype=float))
        lo, hi = min(self.t0, self.t1), max(self.t0, self.t1)
        return bool(np.all((ts >= lo) & (ts <= hi)))

    def raw_states(self, times) -> np.ndarray:
        """States (K, dim) at ``times`` (scalar or (K,), TU, inside the span) in the integration
        frame (no :attr:`transform`). The span's end gives the integrator's end state exactly."""
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        if not self.covers(ts):
            raise StateError(f"dense trajectory over [{self.t0:g}, {self.t1:g}] TU asked for times "
                             f"outside it (from {ts.min():g} to {ts.max():g})")
        dim = self.step_state.shape[1] if self.step_state.ndim == 2 else self.end_state.size
        out = np.empty((ts.size, dim))
        at_end = ts == self.t1
        out[at_end] = self.end_state
        inner = ~at_end
        if np.any(inner):
            key = self._direction * self.step_start
            idx = np.searchsorted(key, self._direction * ts[inner], side="right") - 1
            idx = np.clip(idx, 0, key.size - 1)
            x = ((ts[inner] - self.step_start[idx]) / self.step_size[idx])[:, None]
            c = self.coefficients[idx]  # (k, 7, dim)
            acc = c[:, 6]
            for m in range(5, -1, -1):  # Horner in x and (1 - x), alternating from F6 down
                acc = c[:, m] + (x if m % 2 == 1 else 1.0 - x) * acc
            out[inner] = self.step_state[idx] + x * acc
        return out

    def states(self, times) -> np.ndarray:
        """States (K, dim) at ``times`` (scalar or (K,), TU, inside the span), through
        :attr:`transform` when the model integrates in another frame."""
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        raw = self.raw_states(ts)
        return raw if self.transform is None else self.transform(raw, ts)


def integrate_dense(kernels: ModuleType, state: np.ndarray, t0: float, t1: float, inputs: KernelInputs,
                    label: str) -> DenseTrajectory:
    """Integrate one state (dim,) from ``t0`` to ``t1`` (TU) with ``kernels.dense_kernel``,
    growing the step records as needed. Raises :class:`PropagationError` on the step limit or a
    step-size underflow; ``label`` names the model in the message."""
    dim = state.size
    y = np.array(state, dtype=np.float64).reshape(-1)
    ctl = np.zeros(CTL_SIZE)
    ctl[0] = t0
    parts: list[tuple[np.ndarray, ...]] = []
    cap = 256
    while True:
        rec = (np.empty(cap), np.empty(cap), np.empty((cap, dim)), np.empty((cap, INTERPOLATOR_POWER, dim)))
        ctl[6] = 0.0
        kernels.dense_kernel(y, inputs.params, float(t1), float(inputs.rtol), float(inputs.atol), inputs.body_pos,
                             inputs.body_rad, int(inputs.max_steps), *rec, ctl)
        n = int(ctl[6])
        parts.append(tuple(a[:n] for a in rec))
        status = int(ctl[5])
        if status != 4:
            break
        cap = min(cap * 4, 1 << 20)
    if status in (2, 3):
        why = f"the step limit max_steps={inputs.max_steps}" if status == 2 else "a step-size underflow"
        raise PropagationError(f"{label}: the dense integration from t={t0:g} stopped at t={ctl[0]:g} TU "
                               f"before t={t1:g} ({why})")
    steps = DenseSteps(*(np.concatenate([p[i] for p in parts]) for i in range(4)))
    hit = status == 1
    return DenseTrajectory(t0, float(ctl[0]) if hit else float(t1), steps, y.copy(),
                           impact_body=int(ctl[7]) if hit else -1,
                           impact_time=float(ctl[8]) if hit else np.inf)
