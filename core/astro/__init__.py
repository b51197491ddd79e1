"""Astrodynamics shared by every plugin: primaries and their constants, time scales, the DE421
ephemeris, the real Earth-Moon frame, observatories, topocentric observers, the real-sky model
and multi-site sensor networks.

Imports the base modules, :mod:`cistrack.model`, :mod:`cistrack.interfaces`,
:mod:`cistrack.plugin` and :mod:`cistrack.propagation`.
"""
