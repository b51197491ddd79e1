"""A vectorised Dormand–Prince 5(4) integrator with one step size per particle.

Used by the reference dynamics of the conformance suite. Every particle has its own time, step
size and error estimate, so the result for one particle does not depend on the others (unlike a
single stacked ``solve_ivp`` call, whose RMS error norm loosens the tolerance of individual
particles). The loop is over steps, never over particles.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

__all__ = ["propagate_adaptive"]

# Dormand & Prince (1980) RK5(4)7M coefficients.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = [
    [],
    [1 / 5],
    [3 / 40, 9 / 40],
    [44 / 45, -56 / 15, 32 / 9],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
]
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
_E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])

Rhs = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""rhs(t (n,) TU, y (n, 6)) -> dy/dt (n, 6)."""


def _step(rhs: Rhs, t: np.ndarray, y: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    k = [rhs(t, y)]
    hh = h[:, None]
    for i in range(1, 7):
        yi = y + hh * sum(a * kj for a, kj in zip(_A[i], k) if a != 0.0)
        k.append(rhs(t + _C[i] * h, yi))
    y_new = y + hh * sum(b * kj for b, kj in zip(_B, k) if b != 0.0)
    err = hh * sum(e * kj for e, kj in zip(_E, k) if e != 0.0)
    return y_new, err


def propagate_adaptive(rhs: Rhs, y0: np.ndarray, t0: float, times: Sequence[float],
                       rtol: float = 1e-10, atol: float = 1e-12,
                       impact: Callable[[np.ndarray], np.ndarray] | None = None,
                       max_steps: int = 200_000):
    """Integrate every row of ``y0`` (N, d) from ``t0`` through the output ``times`` (K,).

    ``times`` must all lie on one side of ``t0`` and be monotonic in that direction.
    ``impact(y (n, d)) -> (n,) int`` returns the index of the body a state is inside, or -1;
    a particle that hits stops there (its state is kept for later outputs).

    Returns ``(states (K, N, d), alive (N,), impact_body (N,), impact_time (N,))``.
    """
    y = np.array(y0, dtype=float, copy=True)
    n, d = y.shape
    times = np.asarray(times, dtype=float).reshape(-1)
    out = np.empty((times.size, n, d))
    alive = np.ones(n, dtype=bool)
    body = np.full(n, -1, dtype=int)
    t_hit = np.full(n, np.inf)
    t = np.full(n, float(t0))
    direction = 1.0 if times.size == 0 or times[-1] >= t0 else -1.0
    span = float(np.max(np.abs(times - t0))) if times.size else 0.0
    h = np.full(n, direction * max(span, 1e-12) * 1e-3)
    steps = 0
    for k, tk in enumerate(times):
        while True:
            todo = alive & (direction * (tk - t) > 0.0)
            if not todo.any():
                break
            steps += 1
            if steps > max_steps:
                raise RuntimeError("adaptive integration exceeded its step budget")
            idx = np.flatnonzero(todo)
            hi = h[idx]
            remaining = tk - t[idx]
            last = np.abs(hi) >= np.abs(remaining)
            hi = np.where(last, remaining, hi)
            y_new, err = _step(rhs, t[idx], y[idx], hi)
            scale = atol + rtol * np.maximum(np.abs(y[idx]), np.abs(y_new))
            e = np.sqrt(np.mean((err / scale) ** 2, axis=1))
            ok = e <= 1.0
            factor = np.clip(0.9 * np.where(e > 0, e, 1e-10) ** -0.2, 0.2, 5.0)
            acc = idx[ok]
            y[acc] = y_new[ok]
            t[acc] = np.where(last[ok], tk, t[acc] + hi[ok])
            # Keep the regular step after a shortened final step to an output time.
            h[idx] = np.where(last & ok, h[idx], hi * factor)
            if impact is not None and acc.size:
                hit = impact(y[acc])
                dead = acc[hit >= 0]
                if dead.size:
                    alive[dead] = False
                    body[dead] = hit[hit >= 0]
                    t_hit[dead] = t[dead]
        out[k] = y
    return out, alive, body, t_hit
