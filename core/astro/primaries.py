"""The Earth-Moon system's constants and its primaries, in one place.

Every file that needs the mass ratio or a body radius imports it from here (the frame's units,
LU = 384,400 km and TU = 375,149 s, are in :mod:`cistrack.units`). A dynamics model tells where
its massive bodies are through :attr:`cistrack.interfaces.Dynamics.primaries`; code that needs
"where is the Earth" asks ``dynamics.primary("Earth")`` and "what is the mass ratio"
:func:`mass_ratio`, never a model attribute such as ``mu``.

Constants of the Earth-Moon system used throughout:

- ``MU_EARTH_MOON`` = 1.2150582e-2: m_Moon / (m_Earth + m_Moon) of the synodic frame;
- ``EARTH_RADIUS_KM`` = 6378.137 (WGS-84 equatorial), ``MOON_RADIUS_KM`` = 1737.4 (IAU mean).
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.dynamics import Body
from cistrack.units import LU_KM

__all__ = ["MU_EARTH_MOON", "EARTH_RADIUS_KM", "MOON_RADIUS_KM", "earth_moon_primaries",
           "mass_ratio"]

MU_EARTH_MOON: float = 1.2150582e-2
"""Earth-Moon mass ratio m_Moon / (m_Earth + m_Moon) of the CR3BP synodic frame."""
EARTH_RADIUS_KM: float = 6378.137
"""Earth's equatorial radius, km (the impact surface)."""
MOON_RADIUS_KM: float = 1737.4
"""Moon's mean radius, km (the impact surface)."""


def earth_moon_primaries(mu: float = MU_EARTH_MOON, earth_radius_km: float = EARTH_RADIUS_KM,
                         moon_radius_km: float = MOON_RADIUS_KM) -> tuple[Body, Body]:
    """The Earth and the Moon of the CR3BP synodic frame.

    Earth at (-mu, 0, 0) LU with mass fraction 1 - mu, Moon at (1 - mu, 0, 0) LU with mass
    fraction mu; radii converted from km to LU.
    """
    mu = float(mu)
    return (Body("Earth", np.array([-mu, 0.0, 0.0]), float(earth_radius_km) / LU_KM, 1.0 - mu),
            Body("Moon", np.array([1.0 - mu, 0.0, 0.0]), float(moon_radius_km) / LU_KM, mu))


def mass_ratio(dynamics, default: float = MU_EARTH_MOON) -> float:
    """The Moon's mass fraction among the primaries of ``dynamics`` (``default`` without a Moon)."""
    moon = dynamics.primary("Moon")
    return float(moon.mass_fraction) if moon is not None else float(default)
