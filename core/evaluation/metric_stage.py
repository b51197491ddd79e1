"""The metric stage of a run: step metrics computed in a declared order, before any observer.

A :class:`StepMetric` computes some of a step's metrics (``compute`` returns them as a dict of
name -> float) and names the metrics stages whose values it reads (``needs``). The run's
:class:`MetricStage` calls every stage on each step event in dependency order, merges each result
into ``step.metrics``, and only then hands the step to the observers' lifecycle hooks
(``cistrack_step_predicted`` / ``cistrack_step_updated``), as a :class:`ReadOnlyMetrics`: an
observer that tries to change it raises ``TypeError``.

Built-in stages, in this order: ``belief`` (errors, sigmas, NEES, entropy, truth likelihood:
:class:`cistrack.evaluation.metrics.BeliefMetric`), ``pass_index``, ``information_bound``,
``residuals`` and ``custody`` (needs ``belief``). A plugin adds stages through the
``cistrack_metric_stages(scenario)`` hook; they run after the built-ins unless their ``needs``
say otherwise. A stage may not write a key that an earlier stage wrote.

Events: ``"predicted"`` (the initial IOD cloud, a prediction-only step, or the prior of an update
step: ``step.kind == "update"``) and ``"updated"`` (the posterior of an update step).
"""
from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

from cistrack.errors import ConfigError
from cistrack.interfaces.metric import EVENTS, StepMetric

__all__ = ["StepMetric", "ReadOnlyMetrics", "MetricStage", "order_metrics", "EVENTS"]

class ReadOnlyMetrics(dict):
    """A step's metrics as observers see them: a dict whose contents cannot change. It copies,
    pickles and serialises to JSON as a dict does."""

    def _refuse(self, *args: Any, **kwargs: Any) -> None:
        raise TypeError("step.metrics is read-only: observers must not modify the step; compute a "
                        "metric in a StepMetric stage (the cistrack_metric_stages hook) instead")

    # every method of dict that changes it (their signatures differ; each refuses whatever it is given)
    __setitem__ = __delitem__ = __ior__ = _refuse  # type: ignore[assignment]
    update = pop = popitem = setdefault = clear = _refuse  # type: ignore[assignment]

    def __reduce__(self) -> tuple:
        return (ReadOnlyMetrics, (dict(self),))

    def __copy__(self) -> "ReadOnlyMetrics":
        return self

    def __deepcopy__(self, memo: dict) -> "ReadOnlyMetrics":
        return self


def _check_names(stages: list[StepMetric]) -> dict[str, StepMetric]:
    by_name: dict[str, StepMetric] = {}
    for s in stages:
        if not isinstance(s, StepMetric):
            raise ConfigError(f"metric stage {s!r} is not a cistrack.evaluation.metric_stage.StepMetric")
        if not s.name or s.name in by_name:
            raise ConfigError(f"metric stage {type(s).__name__}: name {s.name!r} is "
                              + ("empty" if not s.name else f"also the name of {type(by_name[s.name]).__name__}"))
        by_name[s.name] = s
    for s in stages:
        unknown = [n for n in s.needs if n not in by_name]
        if unknown:
            raise ConfigError(f"metric stage {s.name!r} needs {', '.join(map(repr, unknown))}, which no stage "
                              f"provides (stages: {', '.join(by_name)})")
    return by_name


def order_metrics(stages: Iterable[StepMetric]) -> list[StepMetric]:
    """The stages in the order given, except that each comes after the stages it ``needs``
    (a stable topological order). Raises ConfigError on a duplicate or empty name, an unknown
    need, or a cycle."""
    todo = list(stages)
    _check_names(todo)
    done: list[StepMetric] = []
    placed: set[str] = set()
    while todo:
        ready = next((s for s in todo if set(s.needs) <= placed), None)
        if ready is None:
            raise ConfigError("metric stages need each other in a cycle: "
                              + "; ".join(f"{s.name} needs {', '.join(s.needs)}" for s in todo))
        todo.remove(ready)
        done.append(ready)
        placed.add(ready.name)
    return done


class MetricStage:
    """Runs a run's ordered :class:`StepMetric` stages on each step event (see the module docstring)."""

    def __init__(self, stages: Iterable[StepMetric]) -> None:
        self.stages = order_metrics(stages)

    def start(self, run: Any) -> None:
        for s in self.stages:
            s.start(run)

    def measure(self, run: Any, step: Any, event: str) -> Any:
        """Compute every stage's metrics of ``step`` at ``event`` into ``step.metrics`` (left
        read-only); returns ``step``. A stage returning a key already present raises ValueError."""
        found: dict[str, float] = dict(step.metrics)
        for s in self.stages:
            step.metrics = ReadOnlyMetrics(found)
            out = s.compute(run, step, event)
            if out:
                again = found.keys() & out.keys()
                if again:  # a programming error of a stage, not a failure of the filter
                    raise ValueError(f"metric stage {s.name!r} writes {', '.join(sorted(again))}, "
                                     "which an earlier stage wrote")
                found.update(out)
        step.metrics = ReadOnlyMetrics(found)
        return step

    def timed(self, run: Any, step: Any, event: str) -> Any:
        """:meth:`measure`, with its time in ``step.timings["metrics"]`` (seconds)."""
        tm = time.perf_counter()
        self.measure(run, step, event)
        step.timings["metrics"] = time.perf_counter() - tm
        return step
