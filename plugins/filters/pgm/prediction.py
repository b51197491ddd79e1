"""The PGM's ``pgm-prediction`` step: propagation of every particle, with optional process noise.

Memory. Propagating N particles at once holds the input states and the propagation's own output
(N, 6) twice, plus its per-particle bookkeeping (about 128 bytes a particle in all). When the
filter hands over particles that nothing else references (``overwrite=True``), they are
propagated in chunks of :data:`PROPAGATION_CHUNK` rows and each chunk's result is written back
over its input: the work arrays are a chunk's. Every particle is integrated on its own (the
kernels' results do not depend on which particles share a call), so the states are the same.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError
from cistrack.interfaces import Dynamics
from cistrack.interfaces.pgm_steps import ParticlePrediction

from ..ensemble_propagation import propagate_ensemble, propagate_particles
from ..process_noise import check_velocity_noise, velocity_random_walk_covariance

__all__ = ["PROPAGATION_CHUNK", "PropagateParticles", "propagate_in_place"]

PROPAGATION_CHUNK = 65_536  # rows propagated per call when the input may be overwritten


class PropagateParticles(ParticlePrediction):
    """Every particle propagated by the dynamics; those that hit a body are dropped; an optional
    velocity random walk is added.

    Parameters
    ----------
    velocity_noise_kms_per_sqrt_day : float
        Velocity random walk, km/s after one day (0 = off).
    """

    overwrites = True  # predict(..., overwrite=True) may write the new states over its input

    def __init__(self, velocity_noise_kms_per_sqrt_day: float = 0.0):
        self.velocity_noise_kms_per_sqrt_day = check_velocity_noise(self, velocity_noise_kms_per_sqrt_day)

    def predict(self, dynamics: Dynamics, states: np.ndarray, t0: float, t1: float, rng: np.random.Generator,
                steps: np.ndarray | None, who: str, overwrite: bool = False
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Survivors (M, 6) at ``t1`` (TU), alive (N,) bool, their next steps (M,) TU or None.
        ``overwrite``: ``states`` (N, 6) float64 and ``steps`` (N,) belong to the caller alone and
        may be overwritten (propagated in chunks, in place: :func:`propagate_in_place`)."""
        if overwrite:
            return propagate_in_place(dynamics, states, t0, t1, who, self.velocity_noise_kms_per_sqrt_day, rng,
                                      steps)
        return propagate_particles(dynamics, states, t0, t1, who, self.velocity_noise_kms_per_sqrt_day, rng, steps)


def propagate_in_place(dynamics: Dynamics, states: np.ndarray, t0: float, t1: float, who: str,
                       velocity_noise_kms_per_sqrt_day: float, rng: np.random.Generator,
                       steps: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """:func:`~cistrack.plugins.filters.ensemble_propagation.propagate_particles`, the same
    results, with ``states`` (N, 6) float64 C-ordered and ``steps`` (N,) float64 (or None)
    overwritten by the propagated ones (and shrunk to the survivors), :data:`PROPAGATION_CHUNK`
    rows per ``dynamics.propagate`` call. ``states`` must own its data; otherwise, or for N up to
    a chunk, it is propagated as by ``propagate_particles``."""
    n, chunk = states.shape[0], PROPAGATION_CHUNK
    if n <= chunk or not (states.dtype == np.float64 and states.flags.c_contiguous and states.flags.owndata
                          and states.flags.writeable):
        return propagate_particles(dynamics, states, t0, t1, who, velocity_noise_kms_per_sqrt_day, rng, steps)
    alive = np.empty(n, dtype=bool)
    h_out = None
    for a in range(0, n, chunk):
        b = min(n, a + chunk)
        x, alive[a:b], h = propagate_ensemble(dynamics, states[a:b], t0, t1, who,
                                              None if steps is None else steps[a:b])
        states[a:b] = x
        if h is not None:
            h_out = _step_array(steps, n) if h_out is None else h_out
            h_out[a:b] = h
        del x, h
    if not np.any(alive):
        raise FilterError(f"filter '{who}': every particle hit a body before t = {t1} TU")
    if not alive.all():  # the survivors moved to the front, in order, and the arrays shortened
        states = _keep_rows(states, alive, chunk)
        h_out = None if h_out is None else _keep_rows(h_out, alive, chunk)
    q = velocity_random_walk_covariance(velocity_noise_kms_per_sqrt_day, t1 - t0, states.shape[1])
    if np.any(q):  # the same normals as one (M, 6) draw: the generator fills row after row
        sd = np.sqrt(np.diag(q))
        for a in range(0, states.shape[0], chunk):
            b = min(states.shape[0], a + chunk)
            states[a:b] += rng.standard_normal((b - a, states.shape[1])) * sd
    return states, alive, h_out


def _keep_rows(a: np.ndarray, keep: np.ndarray, chunk: int) -> np.ndarray:
    """``a[keep]`` for an array ``a`` (N, ...) that nobody else references, made in place: the kept
    rows are moved to the front ``chunk`` rows at a time (a row never overtakes an unread one)
    and ``a`` is shrunk to them, so no second (N, ...) array is made."""
    w = 0
    for s in range(0, a.shape[0], chunk):
        rows = a[s:s + chunk][keep[s:s + chunk]]
        a[w:w + rows.shape[0]] = rows
        w += rows.shape[0]
    a.resize((w,) + a.shape[1:], refcheck=False)  # refcheck: the callers' own references
    return a


def _step_array(steps: np.ndarray | None, n: int) -> np.ndarray:
    """Where the next steps (n,) go: over ``steps`` when it is a writable float64 (n,) array."""
    if (steps is not None and steps.shape == (n,) and steps.dtype == np.float64 and steps.flags.owndata
            and steps.flags.writeable):
        return steps
    return np.empty(n)
