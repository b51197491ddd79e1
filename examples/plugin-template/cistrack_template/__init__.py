"""Example cistrack plugins (a template to copy and rename).

- dynamics ``template-cr3bp-srp``: Earth–Moon CR3BP plus solar radiation pressure
- clustering ``template-bisecting``: bisecting split along principal axes
- iod ``template-two-point``: angles (and optional range) at two epochs, finite-difference velocity
"""
from .bisecting import BisectingClusterer
from .srp import CR3BPSolarPressure
from .two_point import TwoPointIOD

__all__ = ["BisectingClusterer", "CR3BPSolarPressure", "TwoPointIOD"]
__version__ = "0.1.0"
