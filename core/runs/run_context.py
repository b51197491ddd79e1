"""What a run is given and what it hands its observers: the run's options, its context and one step.

Observers (hook implementations of ``cistrack_run_started``, ``cistrack_step_predicted``,
``cistrack_step_updated``, ``cistrack_run_finished``) receive these objects and must treat them
as read-only (a step's metrics are a read-only mapping by the time they see it, and the arrays
of its belief read-only views of the filter's: writing into them raises ValueError).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from cistrack.model.belief import Belief, ParticleCloud
from cistrack.interfaces import Dynamics, Filter, IODMethod, Pass, Schedule, Sensor
from cistrack.model.measurement import Measurement, MeasurementSet
from cistrack.runs.truth import Truth

__all__ = ["RunOptions", "RunContext", "Step"]


@dataclass(frozen=True)
class RunOptions:
    """How :func:`cistrack.runs.pipeline.run_scenario` runs a scenario; the fields are its keywords.

    Attributes
    ----------
    seed : int or None              the scenario's seed when None
    registry : Registry or None     the default registry (installed plugins) when None
    observers : tuple               objects with lifecycle hooks (and ``cistrack_metric_stages``)
    output_dir : Path or None       where a results writer writes the run (none when None)
    progress : bool                 a progress bar on stderr
    run_id : str or None            the scenario's run id when None
    keep_steps : bool               keep the steps themselves in the result
    log : callable or None          receives stage messages (a string each)
    blas_threads : int or None      BLAS threads during the run; None: the run's thread limit
    rows_per_part : int or None     steps per results part file (the default when None)
    residual_figure : bool          with an ``output_dir``, draw its residuals.svg
                                    (:mod:`cistrack.runs.residual_figure`; a few ms)
    """

    seed: int | None = None
    registry: Any = None
    observers: tuple[Any, ...] = ()
    output_dir: Path | None = None
    progress: bool = False
    run_id: str | None = None
    keep_steps: bool = False
    log: Callable[[str], None] | None = None
    blas_threads: int | None = 1
    rows_per_part: int | None = None
    residual_figure: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "observers", tuple(self.observers))
        if self.output_dir is not None:
            object.__setattr__(self, "output_dir", Path(self.output_dir))

    def with_keywords(self, keywords: dict[str, Any]) -> "RunOptions":
        """These options with ``keywords`` (field name -> value) replaced; an unknown name is a
        TypeError that lists the known ones."""
        known = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(keywords) - known)
        if unknown:
            raise TypeError(f"run_scenario() got unexpected keyword argument(s) {', '.join(map(repr, unknown))}; "
                            f"known: {', '.join(sorted(known))}")
        return dataclasses.replace(self, **keywords)


@dataclass
class RunContext:
    """Everything fixed for one run, known before the first filter step.

    Attributes
    ----------
    run_id : str                      e.g. "example-1__pgm__uniform-range__seed1"
    scenario : cistrack.scenario.loading.Scenario
    seed : int
    epoch : datetime                  UTC of t = 0
    dynamics, sensor, schedule, iod, filter : the built components
    truth_times : (K,) float          dense truth grid, TU (also used to find passes)
    truth_states : (K, 6) float       truth on that grid, nondimensional synodic (empty when the
                                      measurements came from a file and truth is unknown)
    truth : Truth or None             every truth state of the run, each propagated once
    truth_impulses : list of Impulse  the burns the truth flies ([truth.maneuvers]; time TU, dv synodic
                                      VU), empty for a ballistic truth; the filter's model knows none
    passes : list of Pass             visibility passes of the truth
    measurements : MeasurementSet     all measurements, including any IOD-only range
    iod_cloud : ParticleCloud         the IOD result (epoch = last fitted measurement)
    output_dir : Path or None         where results of this run are written
    registry : Registry or None       the registry its components came from (messages name a third
                                      party's distribution from it)
    """

    run_id: str
    scenario: Any
    seed: int
    epoch: datetime
    dynamics: Dynamics
    sensor: Sensor
    schedule: Schedule | None
    iod: IODMethod
    filter: Filter
    truth_times: np.ndarray
    truth_states: np.ndarray
    passes: list[Pass]
    measurements: MeasurementSet
    iod_cloud: ParticleCloud
    output_dir: Path | None = None
    truth_dynamics: Dynamics | None = None
    truth: Truth | None = field(default=None, repr=False)
    truth_impulses: list = field(default_factory=list)
    maneuvers: Any = field(default=None, repr=False)
    registry: Any = field(default=None, repr=False)

    @property
    def has_truth(self) -> bool:
        return self.truth is not None

    def truth_at(self, t: float) -> np.ndarray | None:
        """Truth state (6,) at time t (TU), or None without a truth; see :class:`Truth`."""
        return None if self.truth is None else self.truth.at(t)


@dataclass
class Step:
    """One filter step.

    Attributes
    ----------
    index : int                  0 for the IOD cloud, then 1, 2, ... in time order
    t : float                    TU since the epoch
    utc : str                    ISO-8601 UTC of t
    kind : str                   "initial" (IOD cloud), "predict" (no measurement) or "update"
    belief : Belief              prior for "predict" events and predict-only steps, posterior after update;
                                 observers get it with read-only arrays (:meth:`Belief.read_only`)
    truth : (6,) float or None   truth state at t, nondimensional synodic
    measurement : Measurement or None   the measurement used (angles only), for "update" steps;
                                 the first of ``group`` when several share the step's time
    group : tuple of Measurement every measurement of an "update" step (several sites measuring
                                 at one time make one step; the filter takes them in order)
    metrics : dict               metric name -> float (km, m/s, cm/s, nats), computed by the
                                 run's metric stages (:mod:`cistrack.evaluation.metric_stage`)
                                 before the step hooks; read-only when observers see it
    diagnostics : dict           the filter's diagnostics after this step
    timings : dict               stage -> seconds (propagation, update, metrics)
    row : dict or None           its results-table row, once an observer asked for it
    """

    index: int
    t: float
    utc: str
    kind: str
    belief: Belief
    truth: np.ndarray | None = None
    measurement: Measurement | None = None
    group: tuple = ()
    metrics: dict[str, float] = field(default_factory=dict)
    diagnostics: dict[str, float] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    row: dict[str, Any] | None = field(default=None, repr=False, compare=False)
    """Its results-table row, built once by :func:`cistrack.results.step_table.row_of`."""
