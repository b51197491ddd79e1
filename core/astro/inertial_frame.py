"""An Earth-centred inertial frame in which synodic states can be expressed (and a run's estimates
exported).

A sensor says how its synodic frame sits in inertial space through
:meth:`cistrack.interfaces.Sensor.inertial_frame`, returning an :class:`InertialFrame`: a CCSDS
``REF_FRAME`` label (or an honest non-CCSDS one), a one-line description, and the affine map
from nondimensional synodic states at TU times to Earth-centred inertial km, km/s. Covariances
are carried through the exact Jacobian of that map (an affine map has a constant Jacobian per
time, computed here by unit differences).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from cistrack.units import KM_SCALE

__all__ = ["InertialFrame"]


@dataclass(frozen=True)
class InertialFrame:
    """``from_synodic(states (N, 6) nondimensional synodic, t (N,) TU) -> (N, 6) km, km/s``
    (Earth-centred inertial). ``name`` is the REF_FRAME written to CCSDS files; ``ccsds`` says
    whether it is a CCSDS-registered frame; ``center`` the CENTER_NAME."""

    name: str
    description: str
    from_synodic: Callable[[np.ndarray, np.ndarray], np.ndarray]
    ccsds: bool = False
    center: str = "EARTH"
    years: tuple[int, int] | None = None
    """The whole UTC years (first, last) within which ``from_synodic`` holds, when it is drawn from
    an ephemeris of limited span (the real Earth-Moon frame: DE421's); None: at any time."""

    def jacobian(self, state: np.ndarray, t: float) -> np.ndarray:
        """d(inertial km, km/s)/d(synodic km, km/s) at ``state`` (6,) nondimensional: (6, 6)."""
        base = np.asarray(state, dtype=float)[None]
        pts = base + np.vstack([np.zeros(6), np.diag(1.0 / KM_SCALE)])
        out = self.from_synodic(pts, np.full(7, float(t)))
        return (out[1:] - out[0]).T
