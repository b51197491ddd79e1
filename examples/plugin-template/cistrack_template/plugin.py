"""The module named by this package's entry point: registers every component by name.

The names are what scenario files use (``[dynamics] name = "template-cr3bp-srp"``). They must be
unique per kind across every installed plugin, so give yours a prefix of your own.
"""
from cistrack.api import hookimpl

from .bisecting import BisectingClusterer
from .srp import CR3BPSolarPressure
from .two_point import TwoPointIOD


@hookimpl
def cistrack_register(registry):
    registry.add("dynamics", "template-cr3bp-srp", CR3BPSolarPressure)
    registry.add("clustering", "template-bisecting", BisectingClusterer)
    registry.add("iod", "template-two-point", TwoPointIOD)
