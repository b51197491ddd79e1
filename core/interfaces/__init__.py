"""The abstract interfaces every plugin implements, all vectorised over particles.

=============  ==========================================  ==========================
kind           interface                                   registry kind string
=============  ==========================================  ==========================
dynamics       :class:`Dynamics`                           ``"dynamics"``
sensor         :class:`Sensor`                             ``"sensor"``
schedule       :class:`Schedule`                           ``"schedule"``
IOD method     :class:`IODMethod`                          ``"iod"``
clusterer      :class:`Clusterer`                          ``"clustering"``
filter         :class:`Filter`                             ``"filter"``
orbit          :class:`ReferenceOrbit` (data, not a class)  ``"orbit"``
recorder       any object with lifecycle hookimpls         ``"recorder"``
reader         :class:`Reader` (observation file format)   ``"reader"``
exporter       :class:`Exporter` (estimate file format)    ``"exporter"``
range prior    :class:`RangePrior` (IOD range model)        ``"range-prior"``
PGM steps      :class:`ParticlePrediction`,                ``"pgm-prediction"``,
               :class:`ComponentUpdate`,                   ``"pgm-update"``,
               :class:`PosteriorDraw`,                     ``"pgm-draw"``,
               :class:`KernelUpdate`,                      ``"pgm-kernel"``,
               :class:`Reanchor` (:mod:`.pgm_steps`)       ``"pgm-reanchor"``
maneuver plan  :class:`ManeuverPlan` (:mod:`.maneuvers`)   ``"maneuver-plan"``
detector       :class:`ManeuverDetector`                   ``"maneuver-detector"``
response       :class:`ManeuverResponse`                   ``"maneuver-response"``
=============  ==========================================  ==========================

A preset (:func:`~cistrack.interfaces.preset.preset`) registers a component with other defaults.
"""
from cistrack.interfaces.clustering import Clusterer
from cistrack.interfaces.dynamics import Body, Dynamics, Propagation
from cistrack.interfaces.filter import Filter
from cistrack.interfaces.iod import IODMethod
from cistrack.interfaces.maneuvers import Detection, Impulse, ManeuverDetector, ManeuverPlan, ManeuverResponse
from cistrack.interfaces.metric import StepMetric
from cistrack.interfaces.orbit import ReferenceOrbit
from cistrack.interfaces.pgm_steps import ComponentUpdate, KernelUpdate, ParticlePrediction, PosteriorDraw, Reanchor
from cistrack.interfaces.preset import preset
from cistrack.interfaces.exporter import Exporter
from cistrack.interfaces.range_prior import RangePrior
from cistrack.interfaces.reader import Reader
from cistrack.interfaces.schedule import Pass, Schedule
from cistrack.interfaces.sensor import Sensor

KINDS: tuple[str, ...] = ("dynamics", "sensor", "schedule", "iod", "clustering", "filter", "orbit", "recorder", "reader", "exporter", "range-prior",
                         "pgm-prediction", "pgm-update", "pgm-draw", "pgm-kernel", "pgm-reanchor",
                         "maneuver-plan", "maneuver-detector", "maneuver-response")
"""Every registry kind, in the order `cistrack plugins` lists them."""

__all__ = ["Body", "Clusterer", "ComponentUpdate", "Detection", "Dynamics", "Exporter", "Filter", "IODMethod", "KINDS", "StepMetric",
           "Impulse", "KernelUpdate", "ManeuverDetector", "ManeuverPlan", "ManeuverResponse", "ParticlePrediction", "Pass", "PosteriorDraw", "Propagation", "RangePrior", "Reader", "Reanchor", "ReferenceOrbit", "Schedule", "Sensor",
           "preset"]
