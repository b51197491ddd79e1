"""Fast ensemble propagation for any model given as a numba-jitted right-hand side.

A model subclasses :class:`CompiledDynamics`, names its equations of motion in the class
attribute ``rhs`` and returns its constants from :meth:`CompiledDynamics.params_vector`; it
then inherits :meth:`~CompiledDynamics.propagate` (per-particle adaptive DOP853 8(5,3), all
cores, output at many times, forward or backward, impacts on :attr:`bodies`),
:meth:`~CompiledDynamics.dense_trajectory` (one state over a span, evaluated at any time later)
and :meth:`~CompiledDynamics.derivatives`.

Writing a new model in your own package (say a bicircular four-body problem)::

    # mypkg/bcr4bp.py
    import numpy as np
    from numba import njit
    from cistrack.interfaces.component import check_positive
    from cistrack.plugin.hookspecs import hookimpl
    from cistrack.astro.primaries import MU_EARTH_MOON
    from cistrack.propagation import CompiledDynamics

    @njit(cache=True)                      # no fastmath: see dop853_source.DEFAULT_FASTMATH
    def bcr4bp_rhs(t, y, p, out):          # y, out: (6,) float64; p: params_vector()
        mu, ms, a_s, om_s = p[0], p[1], p[2], p[3]
        ...                                # write out[0..5]; no allocation, no Python objects
    class BCR4BP(CompiledDynamics):
        rhs = bcr4bp_rhs                   # a module-level njit function (so it can be cached)
        def __init__(self, mu: float = MU_EARTH_MOON, rtol: float = 1e-11, atol: float = 1e-12):
            self.mu = mu; self.rtol = rtol; self.atol = atol   # validate with check_* here
        def params_vector(self):
            return np.array([self.mu, 328900.54, 388.81, -0.925195985])

    @hookimpl
    def cistrack_register(registry):
        registry.add("dynamics", "bcr4bp", BCR4BP)

and declare ``bcr4bp = "mypkg.bcr4bp"`` under ``[project.entry-points.cistrack]``. The right-hand
side must be a module-level ``@njit`` function ``rhs(t, y, params, out)`` on float64 arrays.
The massive bodies (with their impact radii) come from overriding :attr:`primaries`
(:func:`cistrack.astro.primaries.earth_moon_primaries` for the Earth and the Moon).
Impact bodies that move in the integration frame take their positions from the class attribute
``body_motion``.

Speed: with 4 or more particles the right-hand side runs in the SIMD-lockstep kernel when
:mod:`cistrack.propagation.lane_rhs` can rewrite it: ``y`` and ``out`` indexed by integers
known when the kernel is generated (literals, module constants, the variable of a
``for i in range(<constants>)`` loop, which is unrolled); other loops and branches are fine. A
right-hand side that reads a table by time (``params[j]`` with ``j`` computed from ``t``) marks
the table index ``k: LaneUniform = <int expression of t and params>`` (see
:class:`~cistrack.propagation.lane_rhs.LaneUniform`), or ``k: LaneRecord = ...`` when the index
never goes back as ``t`` grows (a record on a time grid, as in the ephemeris model: cheaper);
otherwise it still runs in lockstep, without SIMD. Anything else falls back to the one-particle kernel (the
reason is logged at debug level). The numbers are the same bit for bit in every case.

How the speed is obtained (generated kernels, their on-disk cache, worker threads) is described
in :mod:`cistrack.propagation.kernels`.
"""
from __future__ import annotations

from types import ModuleType
from typing import Any, ClassVar

import numpy as np

from cistrack.errors import PropagationError, StateError
from cistrack.interfaces.dynamics import Dynamics, Propagation, check_output_times

from cistrack.propagation import background_compile
from cistrack.propagation.dense import DenseTrajectory, KernelInputs, integrate_dense
from cistrack.propagation.kernels import kernels_for, num_threads, run_chunks

__all__ = ["CompiledDynamics", "PropagationError", "StateError", "LOCKSTEP_MIN_PARTICLES"]

LOCKSTEP_MIN_PARTICLES = 4
"""Fewest particles :meth:`CompiledDynamics.propagate` gives the lockstep kernel when that kernel
is not yet compiled here, in numba's cache or in a second process (16 lanes, 32 for a
right-hand side with a table key such as the ephemeris model's; idle lanes repeat an active
one). A full batch costs a quarter to a third of what the one-particle kernel costs for 16
particles (docs/performance.md), so a part-filled batch of 4-5 particles costs about what the
one-particle kernel does. Once the lockstep kernel exists, fewer particles go through it too
(one particle costs 1.3-1.7 times the one-particle kernel's few hundredths of a millisecond,
the same numbers), so a run that also propagates lone states (the least squares' trajectory)
compiles or loads no one-particle kernel; with neither kernel compiled, a lone state compiles
the smaller one-particle kernel."""


# -- the base class ------------------------------------------------------------------------------

class CompiledDynamics(Dynamics):
    """Base class of models given by a numba right-hand side; see the module docstring.

    Subclasses set the class attribute ``rhs`` (an ``@njit`` function ``rhs(t, y, params, out)``
    on float64 arrays, ``y``/``out`` of length ``dim``), implement :meth:`params_vector`, and have
    the instance attributes ``rtol`` and ``atol`` (per-particle relative and absolute error
    tolerances of the integrator, nondimensional). ``max_steps`` (per particle and call) may be
    overridden.
    """

    rhs: ClassVar[Any] = None
    body_motion: ClassVar[Any] = None
    """Optional module-level ``@njit`` function ``(t, params, b, body_pos) -> (x, y, z)``: the
    position of impact body ``b`` at time ``t`` for models whose bodies move in the integration
    frame (the ephemeris model's Moon); ``None`` keeps every body at its :attr:`bodies` position."""
    dim: ClassVar[int] = 6
    max_steps: int = 5_000_000
    carries_steps = True

    def params_vector(self) -> np.ndarray:
        """Model constants handed to ``rhs`` as ``params``, (P,) float64."""
        return np.zeros(1)

    # -- helpers ----------------------------------------------------------------------------------
    def _rhs(self) -> Any:
        """The right-hand side this instance integrates: the class's ``rhs``. A model whose
        configuration switches terms off may return a specialised function giving the same numbers,
        so that its compiled stages carry no switched-off arithmetic (the ephemeris model does)."""
        return type(self).rhs

    def _kernels(self) -> ModuleType:
        rhs = self._rhs()
        if rhs is None or not hasattr(rhs, "py_func"):
            raise TypeError(f"{type(self).__name__}.rhs must be a numba @njit function")
        return kernels_for(rhs, self.dim, type(self).body_motion)

    def _params(self) -> np.ndarray:
        return np.ascontiguousarray(self.params_vector(), dtype=np.float64).reshape(-1)

    def _bodies_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The kernels' impact bodies: positions (B, 5), radii (B,). Columns 0-2 the position,
        column 3 a bound on the body's speed (LU/TU) and column 4 on its acceleration (LU/TU^2)
        in the integration frame: 0 for bodies that stay put, ``inf`` (unknown) for bodies moved
        by ``body_motion``. The lockstep kernel reads a body at rest once per call, and evaluates
        a moving body with a bound on a grid of times at the call's start; a particle farther
        from the chord between two grid positions than the radius plus what the bounds allow
        there is outside the body without evaluating its position: the same decisions."""
        bodies = self.bodies
        pos = np.zeros((max(len(bodies), 1), 5))
        rad = np.zeros(len(bodies))
        for i, b in enumerate(bodies):
            pos[i, :3] = np.asarray(b.position, dtype=float)
            rad[i] = float(b.radius)
        pos[:, 3:] = 0.0 if type(self).body_motion is None else np.inf
        return pos, rad

    def _check_states(self, states: Any) -> np.ndarray:
        try:
            arr = np.asarray(states, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise StateError(f"{self._label()}: states must be a numeric (N, {self.dim}) array: {exc}") from None
        if arr.ndim == 1:
            arr = arr.reshape(1, -1)
        if arr.ndim != 2 or arr.shape[1] != self.dim:
            raise StateError(f"{self._label()}: states must have shape (N, {self.dim}), got {np.shape(states)}")
        if not np.all(np.isfinite(arr)):
            bad = int(np.sum(~np.all(np.isfinite(arr), axis=1)))
            raise StateError(f"{self._label()}: {bad} state(s) contain NaN or inf")
        return np.ascontiguousarray(arr)

    def _check_steps(self, steps: Any, n: int) -> np.ndarray:
        """A fresh (n,) float64 copy of ``steps`` (zeros for None), which the kernel overwrites."""
        if steps is None:
            return np.zeros(n)
        h = np.array(steps, dtype=np.float64).reshape(-1)
        if h.shape != (n,) or not np.all(np.isfinite(h)):
            raise StateError(f"{self._label()}: steps must be {n} finite step sizes (TU), one per "
                             f"state, got shape {np.shape(steps)}")
        return h

    # -- Dynamics ---------------------------------------------------------------------------------
    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of ``states`` (N, dim) [LU, VU] at ``t`` (TU) -> (N, dim) [VU, VU/TU]."""
        arr = self._check_states(states)
        out = np.empty_like(arr)
        self._kernels().derivatives_kernel(float(t), arr, self._params(), out)
        return out

    def propagate(self, states: np.ndarray, t0: float, times: Any, *,
                  rtol: float | None = None, atol: float | None = None,
                  steps: np.ndarray | None = None) -> Propagation:
        """Propagate ``states`` (N, dim) from ``t0`` to each of ``times`` (scalar or (K,), TU).

        Every particle is integrated with its own adaptive step and error control (DOP853,
        tolerances ``rtol``/``atol``, default the model's); with at least
        :data:`LOCKSTEP_MIN_PARTICLES` particles and a right-hand side the generator can rewrite,
        in SIMD lockstep (bit-identical results). ``times`` must all lie on one side of
        ``t0`` and be monotonic away from it (backward propagation: all earlier). Returns a
        :class:`~cistrack.interfaces.dynamics.Propagation` with ``states`` (K, N, dim); particles
        that hit a body are frozen at the located impact point with ``alive`` False.

        ``steps`` (N,) TU, optional: each particle's first step size (non-positive entries: chosen
        by the integrator's initial-step estimate, as without ``steps``), typically the
        ``Propagation.steps`` of the previous call. The result's ``steps`` holds the step size
        each particle's error control proposes next (the input's entry for particles that took no
        step, 0 for those that hit a body). Carrying it saves the initial-step estimate, about
        40 % of a call over a few hours; results then differ from a fresh start at the level of
        the tolerance.

        Raises :class:`StateError` for malformed input and :class:`PropagationError` if a particle
        exhausts ``max_steps`` or its step size underflows.
        """
        arr = self._check_states(states)
        t0, t_out = self._check_output_times(t0, times)
        rtol = float(self.rtol if rtol is None else rtol)
        atol = float(self.atol if atol is None else atol)
        n = arr.shape[0]
        h = self._check_steps(steps, n)
        out = np.empty((t_out.size, n, self.dim))
        impact_body = np.full(n, -1, dtype=np.int64)
        impact_time = np.full(n, np.inf)
        status = np.zeros(n, dtype=np.int64)
        pos, rad = self._bodies_arrays()
        if n:
            run_chunks(self._propagate_kernel(n), n,
                       (arr, self._params(), t0, np.ascontiguousarray(t_out), rtol, atol, pos, rad,
                        int(self.max_steps), h, out, impact_body, impact_time, status))
        self._raise_failed(status, n, t_out)
        h[impact_body >= 0] = 0.0
        return Propagation(times=t_out, states=out, alive=impact_body < 0,
                           impact_body=impact_body, impact_time=impact_time, steps=h)

    def _check_output_times(self, t0: float, times: Any) -> tuple[float, np.ndarray]:
        """``t0`` as a float and ``times`` as (K,) float64: finite, at least one, monotonic away from t0."""
        return check_output_times(self._label(), t0, times)

    def _propagate_kernel(self, n: int) -> Any:
        """The SIMD-lockstep kernel when the model has one and it exists already or ``n`` particles
        fill enough lanes (:data:`LOCKSTEP_MIN_PARTICLES`; the same numbers), else the
        per-particle kernel."""
        mod = self._kernels()
        lockstep = getattr(mod, "propagate_lanes_kernel", None)
        if lockstep is not None and (n >= LOCKSTEP_MIN_PARTICLES or background_compile.lockstep_available(mod)):
            background_compile.wait_for(mod)
            return lockstep
        return mod.propagate_kernel

    def _raise_failed(self, status: np.ndarray, n: int, t_out: np.ndarray) -> None:
        """PropagationError when a particle hit the step limit (status 2) or underflowed (3)."""
        failed = status >= 2
        if np.any(failed):
            limit = int(np.sum(status == 2))
            under = int(np.sum(status == 3))
            raise PropagationError(
                f"{self._label()}: {int(failed.sum())} of {n} particle(s) did not reach t={t_out[-1]:g} TU "
                f"({limit} hit the step limit max_steps={self.max_steps}, {under} had step-size underflow)")

    def dense_trajectory(self, state: np.ndarray, t0: float, t1: float, *,
                         rtol: float | None = None, atol: float | None = None) -> DenseTrajectory:
        """Propagate one ``state`` (dim,) from ``t0`` to ``t1`` (TU) once, keeping the dense output.

        The steps are those :meth:`propagate` takes to the single time ``t1`` (same tolerances,
        same impact location; the state at ``t1`` is bit-identical); the returned
        :class:`~cistrack.propagation.dense.DenseTrajectory` gives the state at any time of the
        span from each step's 7th-order interpolant. A particle that hits a body ends the span at
        the impact (``alive`` False). Raises :class:`StateError` for malformed input and
        :class:`PropagationError` if the step limit is reached or the step size underflows.
        """
        arr = self._check_states(state)
        if arr.shape[0] != 1:
            raise StateError(f"{self._label()}: dense_trajectory takes one state ({self.dim},), got {arr.shape[0]}")
        t0, t1 = float(t0), float(t1)
        if not (np.isfinite(t0) and np.isfinite(t1)):
            raise StateError(f"{self._label()}: t0 and t1 must be finite")
        num_threads()  # one particle runs on one thread, but a bad CISTRACK_NUM_THREADS is refused here too
        pos, rad = self._bodies_arrays()
        inputs = KernelInputs(self._params(), float(self.rtol if rtol is None else rtol),
                              float(self.atol if atol is None else atol), pos, rad, int(self.max_steps))
        return integrate_dense(self._kernels(), arr[0], t0, t1, inputs, self._label())
