"""Reference orbits: named initial states registered under the kind "orbit"."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ReferenceOrbit"]


@dataclass(frozen=True)
class ReferenceOrbit:
    """A named initial state.

    Attributes
    ----------
    name : str
    state : (6,) float    nondimensional synodic state at t = 0
    period : float | None period in TU for periodic orbits, None otherwise
    mu : float            mass ratio the state was corrected for
    description : str     one line
    """

    name: str
    state: np.ndarray
    period: float | None
    mu: float
    description: str
