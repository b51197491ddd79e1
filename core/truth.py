"""The true trajectory of a simulated run: every truth state is propagated once.

A run needs the truth in three waves, each known only after the one before:

1. on the dense grid (``truth_grid_minutes``), to find the visibility passes;
2. at the measurement times the schedule picks inside those passes, to simulate measurements;
3. at the filter's step times, for the metrics. Most are measurement times (already known);
   prediction-only steps (``predict_every_hours``, counted from the IOD epoch) and the final
   prediction add new ones.

:class:`Truth` owns all of it: :meth:`Truth.states_at` propagates only the times it has not
computed yet, all of them in one ``propagate`` call from the initial state (so a run makes at
most three propagate calls on the truth dynamics, one per wave, and never computes a time
twice); afterwards every state is a look-up. Propagating each wave from the initial state,
rather than from the nearest known state, keeps the measurements bit-identical to those of a
single propagation to the measurement times.

One call for all three waves is impossible without a dense-output integrator: the measurement
times depend on the passes, which depend on the truth. (Per-particle DOP853 dense output would
allow it; the kernels do not provide it.)
"""
from __future__ import annotations

import numpy as np

from . import units
from .errors import ConfigError
from .interfaces.dynamics import Dynamics

__all__ = ["Truth"]


class Truth:
    """The truth trajectory from ``x0`` (6,) at ``t0`` (TU) under ``dynamics``.

    Attributes
    ----------
    dynamics : Dynamics   the truth model (may differ from the filter's)
    x0 : (6,) float       initial state, nondimensional synodic
    t0 : float            TU since the scenario epoch
    propagations : int    number of propagate calls made so far
    """

    def __init__(self, dynamics: Dynamics, x0: np.ndarray, t0: float = 0.0) -> None:
        self.dynamics = dynamics
        self.x0 = np.array(x0, dtype=float).reshape(6)
        self.t0 = float(t0)
        self.propagations = 0
        self._states: dict[float, np.ndarray] = {self.t0: self.x0.copy()}

    @property
    def known_times(self) -> np.ndarray:
        """Every time (TU) whose state has been computed, sorted, (K,)."""
        return np.array(sorted(self._states))

    def states_at(self, times) -> np.ndarray:
        """Truth states (K, 6) at ``times`` (scalar or (K,) TU, each >= t0, in any order).

        Times not computed before are propagated together in one call; a truth that hits a body
        raises :class:`~cistrack.errors.ConfigError` naming the body and the time.
        """
        ts = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
        if np.any(ts < self.t0) or not np.all(np.isfinite(ts)):
            raise ValueError(f"truth times must be finite and >= t0 = {self.t0} TU")
        new = np.unique([t for t in ts.tolist() if t not in self._states])
        if new.size:
            prop = self.dynamics.propagate(self.x0[None], self.t0, new)
            self.propagations += 1
            if not prop.alive[0]:
                bodies = self.dynamics.bodies
                b = int(prop.impact_body[0])
                name = bodies[b].name if 0 <= b < len(bodies) else "a body"
                raise ConfigError(f"the truth trajectory hits {name} at t = "
                                  f"{units.tu_to_days(prop.impact_time[0]):.3f} days; shorten duration_days")
            for t, x in zip(new.tolist(), prop.states[:, 0, :]):
                self._states[t] = x.copy()
        return np.stack([self._states[t] for t in ts.tolist()])

    def at(self, t: float) -> np.ndarray:
        """Truth state (6,) at ``t`` (TU); a look-up once the time is known."""
        return self.states_at(float(t))[0].copy()
