"""Every component of this package passes cistrack's conformance suite (one test per check)."""
from cistrack.testing import parametrize_with_checks

from cistrack_template import BisectingClusterer, CR3BPSolarPressure, TwoPointIOD


@parametrize_with_checks([CR3BPSolarPressure, BisectingClusterer, TwoPointIOD])
def test_conformance(component, check):
    check(component)
