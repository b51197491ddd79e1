"""The sensor-area plugins pass cistrack's conformance suite (cistrack.testing)."""
from __future__ import annotations

from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.plugins.sensors.space_telescope import SpaceTelescope
from cistrack.plugins.sensors.schedules import (
    EverySchedule, PaperExample1Schedule, PaperExample2Schedule, PaperExample3Schedule, PhasedSchedule,
    RandomConsecutiveSchedule,
)
from cistrack.testing import parametrize_with_checks


@parametrize_with_checks([GroundTelescope, GroundTelescope(measure_range=True), GroundTelescope(angles="radec"),
                          GroundTelescope(visibility={"sun_max_elevation_deg": -12.0, "limiting_magnitude": 18.0}),
                          SpaceTelescope,
                          SpaceTelescope(measure_range=True, measure_range_rate=True), PhasedSchedule,
                          EverySchedule, RandomConsecutiveSchedule, PaperExample1Schedule,
                          PaperExample2Schedule, PaperExample3Schedule])
def test_conformance(component, check):
    check(component)
