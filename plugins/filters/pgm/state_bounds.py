"""Optional pruning of particles outside cislunar space (paper section 2: range from the
Earth between 84,328 km and 550,000 km, speed at most 42 km/s)."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces import Dynamics
from cistrack.model.belief import GaussianMixture
from cistrack.units import LU_KM, VU_KMS

__all__ = ["StateBounds", "earth_position", "sample_inside"]

_REDRAWS = 10  # attempts to replace drawn particles that fall outside the state bounds


def earth_position(dynamics: Dynamics) -> np.ndarray:
    """Synodic position (3,) LU of the Earth: the dynamics' primary named 'Earth' (at t = 0),
    else the origin (a model without an Earth measures ranges from its origin)."""
    earth = dynamics.primary("Earth")
    return np.zeros(3) if earth is None else earth.position_at(0.0).copy()


class StateBounds:
    """Admissible states: Earth distance in [min_range_km, max_range_km] and synodic speed at most
    max_speed_kms; any bound None is not applied."""

    def __init__(self, min_range_km: float | None, max_range_km: float | None, max_speed_kms: float | None,
                 earth: np.ndarray):
        self.min_r = None if min_range_km is None else min_range_km / LU_KM
        self.max_r = None if max_range_km is None else max_range_km / LU_KM
        self.max_v = None if max_speed_kms is None else max_speed_kms / VU_KMS
        self.earth = np.asarray(earth, dtype=float)

    @property
    def active(self) -> bool:
        return not (self.min_r is None and self.max_r is None and self.max_v is None)

    def admissible(self, states: np.ndarray) -> np.ndarray:
        """(N,) bool for states (N, 6)."""
        ok = np.ones(states.shape[0], dtype=bool)
        if self.min_r is not None or self.max_r is not None:
            r = np.linalg.norm(states[:, :3] - self.earth, axis=1)
            if self.min_r is not None:
                ok &= r >= self.min_r
            if self.max_r is not None:
                ok &= r <= self.max_r
        if self.max_v is not None:
            ok &= np.linalg.norm(states[:, 3:6], axis=1) <= self.max_v
        return ok


def sample_inside(post: GaussianMixture, n: int, rng: np.random.Generator,
                  bounds: StateBounds) -> tuple[np.ndarray, np.ndarray, int]:
    """Up to ``n`` draws (n', 6) from ``post`` inside ``bounds``, their components (n',), and how
    many draws fell outside. Draws outside are replaced by further draws (at most 10 rounds, each
    drawing twice the shortfall plus 8 to cover the rejection rate); n' < n only when they all fail."""
    x, lab = post.sample(n, rng)
    if not bounds.active:
        return x, lab, 0
    ok = bounds.admissible(x)
    x, lab = x[ok], lab[ok]
    pruned = n - x.shape[0]
    for _ in range(_REDRAWS):
        short = n - x.shape[0]
        if short == 0:
            break
        extra, elab = post.sample(short * 2 + 8, rng)
        ok = bounds.admissible(extra)
        pruned += int(np.count_nonzero(~ok))
        x = np.concatenate([x, extra[ok][:short]])
        lab = np.concatenate([lab, elab[ok][:short]])
    return x, lab, pruned
