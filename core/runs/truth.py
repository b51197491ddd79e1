"""The true trajectory of a simulated run: the truth is propagated once.

A run needs the truth in three waves, each known only after the one before:

1. on the dense grid (``truth_grid_minutes``), to find the visibility passes;
2. at the measurement times the schedule picks inside those passes, to simulate measurements;
3. at the filter's step times, for the metrics (measurement times, prediction-only steps and the
   final prediction).

:class:`Truth` propagates the truth once, over the whole scenario span ``[t0, t_end]``, keeping
the integrator's dense output (:meth:`CompiledDynamics.dense_trajectory
<cistrack.propagation.CompiledDynamics.dense_trajectory>`); every wave is then an evaluation of
the DOP853 7th-order interpolant, accurate to the integrator's own error (a few 1e-10 LU/VU over
a 9:2 NRHO period at the default tolerance; tests/propagation/test_dense_output.py). A time past
``t_end`` extends the span with one more propagation (counted in ``propagations``).

A truth model without ``dense_trajectory`` (a third-party :class:`Dynamics` that is not a
``CompiledDynamics``) falls back to one ``propagate`` call per wave from the initial state,
each time computed once.
"""
from __future__ import annotations

import numpy as np

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.interfaces.dynamics import Dynamics

__all__ = ["Truth"]


class Truth:
    """The truth trajectory from ``x0`` (6,) at ``t0`` (TU) under ``dynamics``.

    Attributes
    ----------
    dynamics : Dynamics   the truth model (may differ from the filter's)
    x0 : (6,) float       initial state, nondimensional synodic
    t0 : float            TU since the scenario epoch
    t_end : float or None TU: the span propagated at the first request (the scenario's duration);
                          None: up to the latest time asked for
    impulses : list       the burns the truth flies (``dynamics.impulses`` of an
                          :class:`~cistrack.propagation.impulses.ImpulsiveDynamics`), else empty
    propagations : int    number of propagations made so far (one per run when ``t_end`` covers
                          every time asked for)
    """

    def __init__(self, dynamics: Dynamics, x0: np.ndarray, t0: float = 0.0, t_end: float | None = None) -> None:
        self.dynamics = dynamics
        self.x0 = np.array(x0, dtype=float).reshape(6)
        self.t0 = float(t0)
        self.t_end = None if t_end is None else float(t_end)
        self.propagations = 0
        self.impulses = list(getattr(dynamics, "impulses", None) or [])
        self._states: dict[float, np.ndarray] = {self.t0: self.x0.copy()}
        self._dense = None
        self._known: set[float] = {self.t0}

    @property
    def known_times(self) -> np.ndarray:
        """Every time (TU) whose state has been asked for (or computed), sorted, (K,)."""
        return np.array(sorted(self._known | set(self._states)))

    def states_at(self, times) -> np.ndarray:
        """Truth states (K, 6) at ``times`` (scalar or (K,) TU, each >= t0, in any order).

        A truth that hits a body raises :class:`~cistrack.errors.ConfigError` naming the body and
        the time.
        """
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        if np.any(ts < self.t0) or not np.all(np.isfinite(ts)):
            raise ValueError(f"truth times must be finite and >= t0 = {self.t0} TU")
        if callable(getattr(self.dynamics, "dense_trajectory", None)):
            return self._dense_states(ts)
        new = np.unique([t for t in ts.tolist() if t not in self._states])
        if new.size:
            prop = self.dynamics.propagate(self.x0[None], self.t0, new)
            self.propagations += 1
            if not prop.alive[0]:
                self._impact(int(prop.impact_body[0]), float(prop.impact_time[0]))
            for t, x in zip(new.tolist(), prop.states[:, 0, :]):
                self._states[t] = x.copy()
        return np.stack([self._states[t] for t in ts.tolist()])

    def _dense_states(self, ts: np.ndarray) -> np.ndarray:
        if self._dense is None or (ts.size and ts.max() > self._dense.t1):
            end = max([float(ts.max()) if ts.size else self.t0]
                      + ([self.t_end] if self.t_end is not None else [])
                      + ([self._dense.t1] if self._dense is not None else []))
            self._dense = self.dynamics.dense_trajectory(self.x0, self.t0, end)
            self.propagations += 1
            if not self._dense.alive:
                self._impact(self._dense.impact_body, self._dense.impact_time)
        self._known.update(ts.tolist())
        return self._dense.states(ts)

    def _impact(self, b: int, t: float) -> None:
        bodies = self.dynamics.bodies
        name = bodies[b].name if 0 <= b < len(bodies) else "a body"
        if t <= self.t0:
            raise ConfigError(f"the truth's initial state lies inside {name}; give [truth] a state outside it")
        raise ConfigError(f"the truth trajectory hits {name} at t = "
                          f"{units.tu_to_days(t):.3f} days; shorten duration_days")

    def at(self, t: float) -> np.ndarray:
        """Truth state (6,) at ``t`` (TU); an evaluation once the span is propagated."""
        return self.states_at(float(t))[0].copy()
