"""The paper's three kinematic-fit IOD variants as presets of :class:`.kinematic.KinematicFitIOD`
(registered as iod "noisy-range", "uniform-range" and "uniform-range-velocity-bound"): each fixes
the range prior (and the speed bound) and keeps the other parameters, so a preset gives the same
cloud as the composed component with the same seed.
"""
from __future__ import annotations

from cistrack.api import hookimpl, preset

from .kinematic import KinematicFitIOD
from .range_priors import NoisyRange, UniformRange
from .tracklet_ranging import TrackletRangingIOD

__all__ = ["NoisyRangeIOD", "UniformRangeIOD", "UniformRangeVelocityBoundIOD"]

_NO_SPEED_BOUND = {"max_speed_kms": None, "speed_frame": "topocentric"}
_UNIFORM = {"range_prior": (UniformRange, ("range_min_km", "range_max_km"))}

NoisyRangeIOD = preset(
    KinematicFitIOD, "NoisyRangeIOD",
    'Preset "noisy-range": kinematic-fit with ``range_prior = noisy(alpha)``, no speed bound.',
    nested={"range_prior": (NoisyRange, ("alpha",))}, fixed=_NO_SPEED_BOUND)

UniformRangeIOD = preset(
    KinematicFitIOD, "UniformRangeIOD",
    'Preset "uniform-range": kinematic-fit with ``range_prior = uniform`` between the range bounds, no speed bound.',
    nested=_UNIFORM, fixed=_NO_SPEED_BOUND)

UniformRangeVelocityBoundIOD = preset(
    KinematicFitIOD, "UniformRangeVelocityBoundIOD",
    'Preset "uniform-range-velocity-bound": uniform-range plus the speed bound ``max_speed_kms`` '
    "(42 km/s in the topocentric frame, the paper's).",
    nested=_UNIFORM, oversampling=10.0, max_oversampling=100.0, max_speed_kms=42.0)


@hookimpl
def cistrack_register(registry) -> None:
    """The composed component and its three presets, in this order (this module is the entry point
    ``kinematic-fit``: registering here keeps kinematic.py free of an import of its presets), then
    "tracklet-ranging" (:mod:`.tracklet_ranging`, the fallback of ``cistrack fit`` for short
    first passes; registered here so that no new entry point has to be installed)."""
    registry.add("iod", "kinematic-fit", KinematicFitIOD)
    registry.add("iod", "noisy-range", NoisyRangeIOD)
    registry.add("iod", "uniform-range", UniformRangeIOD)
    registry.add("iod", "uniform-range-velocity-bound", UniformRangeVelocityBoundIOD)
    registry.add("iod", "tracklet-ranging", TrackletRangingIOD)
