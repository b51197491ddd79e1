"""Maneuvers: impulsive burns in a truth (``maneuver-plan``) and their detection (``maneuver-detector``).

An :class:`Impulse` is a velocity change applied instantaneously at one time, as a synodic vector
(VU): the form every dynamics model can apply (a propagation stops at the burn, adds ``dv`` to
the velocity and goes on). A :class:`ManeuverPlan` turns a scenario's description of burns
(a time and a vector in a local frame, or a rule such as "once per revolution near apolune")
into impulses along the ballistic truth.

A :class:`ManeuverDetector` watches a filter's innovations, one update at a time: given the prior
belief, the measurements taken at one time and the sensor, it returns a :class:`Detection` when
the measurements are unlikely under the prior in a way a burn explains, else None.

A :class:`ManeuverResponse` is what a run does about a detection before the filter takes the
measurements that raised it: a new cloud of particles at the detection time (the prior widened
by the burns it may have made), from which the filter starts again; or nothing. A response that
sets ``needs_history = True`` is also handed a :class:`ResponseHistory`: the measurements taken
before the detection, the sensor, and the filter's settled posterior before the suspect interval.
"""
from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from cistrack.interfaces.component import Component
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.sensor import Sensor
from cistrack.model.belief import Belief, ParticleCloud
from cistrack.model.measurement import Measurement, MeasurementSet

__all__ = ["Impulse", "ManeuverPlan", "Detection", "ManeuverDetector", "ManeuverResponse", "SettledPosterior",
           "ResponseHistory"]


@dataclass(frozen=True)
class Impulse:
    """One impulsive burn.

    Attributes
    ----------
    t : float             TU since the scenario epoch
    dv : (3,) float       velocity change, synodic frame, VU (``cistrack.units.VU_KMS`` km/s per VU)
    label : str           a name for reports ("burn 1", "station-keeping 2")
    """

    t: float
    dv: np.ndarray
    label: str = ""

    def __post_init__(self) -> None:
        dv = np.asarray(self.dv, dtype=float).reshape(-1)
        if not np.isfinite(self.t):
            raise ValueError(f"impulse {self.label!r}: t = {float(self.t)!r} TU is not a finite number")
        if dv.shape != (3,) or not np.all(np.isfinite(dv)):
            raise ValueError(f"impulse {self.label!r}: dv = {dv.tolist()} is not 3 finite numbers (synodic VU)")
        object.__setattr__(self, "dv", dv)


class ManeuverPlan(Component):
    """The burns of a truth trajectory (registry kind ``"maneuver-plan"``, scenario table
    ``[truth.maneuvers]``)."""

    kind = "maneuver-plan"

    @abstractmethod
    def impulses(self, dynamics: Dynamics, x0: np.ndarray, t0: float, t_end: float) -> list[Impulse]:
        """The impulses (sorted by time, each in ``(t0, t_end]``) of a truth that starts at ``x0``
        (6,) at ``t0`` TU under ``dynamics``. A plan whose burns are given in a local frame
        (radial/in-track/cross-track, velocity-normal-binormal) resolves them along the trajectory
        flown with the earlier impulses applied."""

    def burns_outside(self, t0: float, t_end: float) -> list[str]:
        """The burns the plan gives outside ``(t0, t_end]`` TU (so not flown), one short
        description each ('burn 2 at 5 days'); the run's log names them. Default: none known."""
        return []


@dataclass
class Detection:
    """A maneuver detected at one update.

    Attributes
    ----------
    t : float                       TU of the update that raised it
    statistic : float               the detector's test statistic there
    threshold : float               the value it crossed
    detector : str                  the detector's registered name
    t_burn : float or None          TU, the estimated burn time, where the detector estimates it
    t_burn_bounds : (float, float)  TU, the interval the burn lies in (the last update judged
                                    consistent, and ``t``)
    delta_v : (3,) float or None    estimated velocity change, synodic VU
    delta_v_covariance : (3, 3) or None  its covariance, VU^2
    """

    t: float
    statistic: float
    threshold: float
    detector: str = ""
    t_burn: float | None = None
    t_burn_bounds: tuple[float, float] = (float("nan"), float("nan"))
    delta_v: np.ndarray | None = None
    delta_v_covariance: np.ndarray | None = None
    extra: dict = field(default_factory=dict)


class ManeuverDetector(Component):
    """A sequential maneuver test on a filter's innovations (registry kind ``"maneuver-detector"``).

    Lifecycle: :meth:`reset` once per run, then :meth:`observe` at every update, in time order,
    with the prior belief (before the update). After a detection the detector starts a new test
    (it does not fire again on the same evidence).
    """

    kind = "maneuver-detector"

    @abstractmethod
    def reset(self) -> None:
        """Forget everything seen (a new run)."""

    @abstractmethod
    def observe(self, t: float, prior: Belief, measurements: Sequence[Measurement],
                sensor: Sensor) -> tuple[float, Detection | None]:
        """Judge the ``measurements`` (taken at ``t`` TU, one or several sites) against the
        ``prior`` belief, each predicted by ``sensor.for_measurement(m)`` where the sensor has it.
        Returns (the test statistic after this update, a :class:`Detection` or None)."""


@dataclass(frozen=True)
class SettledPosterior:
    """One of the filter's posteriors, as a Gaussian.

    Attributes
    ----------
    t : float                  TU, the update it follows
    mean : (6,) float          synodic LU, VU
    covariance : (6, 6) float  LU, VU squared
    """

    t: float
    mean: np.ndarray
    covariance: np.ndarray


def _quiet(message: str) -> None:
    """Say nothing (a history built without a log)."""


@dataclass(frozen=True)
class ResponseHistory:
    """What a run saw before a detection, handed to a response with ``needs_history = True``.

    Attributes
    ----------
    measurements : MeasurementSet   every measurement taken before the detection's time (TU, rad;
                                    not those at it: the filter takes them after the response)
    sensor : Sensor                 the sensor (or site network) that took them
    posterior : SettledPosterior or None   the filter's latest settled posterior (largest position
                                    sigma below ``cistrack.runs.maneuver_watch.SETTLED_KM``) at or
                                    before ``PRE_DAYS`` before the suspect interval (else the
                                    earliest settled one inside it); None when there is none
    say : callable(str)             the run's log, for what the response did in words
    """

    measurements: MeasurementSet
    sensor: Sensor
    posterior: SettledPosterior | None = None
    say: Callable[[str], None] = _quiet


class ManeuverResponse(Component):
    """What a run does when a maneuver is detected (registry kind ``"maneuver-response"``).

    Called once per detection, before the filter's update with the measurements that raised it.

    A response that sets the class attribute ``needs_history = True`` is called as
    ``respond(detection, prior, dynamics, rng, history=ResponseHistory(...))`` (the measurements
    before ``detection.t``, the sensor, the settled posterior before the suspect interval); it must
    still work with ``history=None`` (a call outside a run). With ``needs_history = False`` (the
    default) the call has the four arguments only.
    """

    kind = "maneuver-response"
    needs_history: bool = False

    @abstractmethod
    def respond(self, detection: Detection, prior: Belief, dynamics: Dynamics,
                rng: np.random.Generator) -> ParticleCloud | None:
        """A cloud (N, 6) at ``detection.t`` (TU) from which the filter starts again, or None to
        leave the filter as it is. ``prior`` is the filter's belief at ``detection.t`` before the
        update; ``dynamics`` the filter's model; every random draw comes from ``rng``. A response
        with ``needs_history = True`` takes a fifth keyword argument ``history``
        (:class:`ResponseHistory` or None)."""
