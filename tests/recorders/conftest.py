"""A small real run (cr3bp, ground telescope, noisy-range IOD, PGM) recorded by two rerun
recorders, plus an observer that keeps a copy of what every hook received."""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from cistrack import units
from cistrack.plugin.hookspecs import hookimpl
from cistrack.plugin.registry import load_registry
from cistrack.results.store import read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import parse_scenario

NRHO_9_2 = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])
N_PARTICLES = 300
SMALL_MAX_POINTS = 50
FEW_ELLIPSOIDS = 2


@dataclass
class Event:
    hook: str
    index: int
    kind: str
    t: float
    states: np.ndarray
    labels: np.ndarray | None
    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    truth: np.ndarray | None
    has_measurement: bool
    metrics: dict


class EventLog:
    """Keeps a deep copy of the belief each lifecycle hook received, in call order."""

    def __init__(self) -> None:
        self.events: list[Event] = []

    def _keep(self, hook: str, step) -> None:
        s, m = step.belief.samples, step.belief.mixture
        self.events.append(Event(hook, step.index, step.kind, step.t, s.states.copy(),
                                 None if s.labels is None else np.asarray(s.labels).copy(),
                                 m.weights.copy(), m.means.copy(), m.covariances.copy(),
                                 None if step.truth is None else np.asarray(step.truth).copy(),
                                 step.measurement is not None, copy.deepcopy(step.metrics)))

    @hookimpl
    def cistrack_step_predicted(self, run, step):
        self._keep("predicted", step)

    @hookimpl
    def cistrack_step_updated(self, run, step):
        self._keep("updated", step)


@dataclass
class RecordedRun:
    full_rrd: Path
    small_rrd: Path
    few_ellipsoids_rrd: Path
    result: object
    table: object
    log: EventLog
    registry: object


def small_scenario(registry):
    data = {
        "name": "recorder-test", "epoch": "2026-01-01T00:00:00Z", "seed": 3, "duration_days": 1.0,
        "truth": {"state_km": [float(v) for v in units.state_to_km(NRHO_9_2)]},
        "dynamics": {"name": "cr3bp"},
        "sensor": {"name": "ground-telescope", "measure_range": True},
        "schedule": {"name": "every", "interval_minutes": 15.0, "end_hours": 6.0},
        "iod": {"name": "noisy-range", "n_particles": N_PARTICLES},
        "filter": {"name": "pgm", "n_particles": N_PARTICLES, "n_components": 3},
    }
    return parse_scenario(data, registry=registry)


@pytest.fixture(scope="session")
def recorded_run(tmp_path_factory) -> RecordedRun:
    reg = load_registry()
    scen = small_scenario(reg)
    d = tmp_path_factory.mktemp("recorded")
    full = reg.create("recorder", "rerun", path=str(d / "full.rrd"), max_points=100_000)
    small = reg.create("recorder", "rerun", path=str(d / "small.rrd"), max_points=SMALL_MAX_POINTS)
    few = reg.create("recorder", "rerun", path=str(d / "few.rrd"), max_ellipsoids=FEW_ELLIPSOIDS)
    log = EventLog()
    res = run_scenario(scen, registry=reg, observers=[full, small, few, log], output_dir=d / "out")
    return RecordedRun(d / "full.rrd", d / "small.rrd", d / "few.rrd", res, read_steps(d / "out"), log, reg)
