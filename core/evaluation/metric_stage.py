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

import numpy as np

from cistrack.errors import CistrackError, ConfigError, PluginError, exception_text
from cistrack.interrupts import plugin_fault
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


_PASS_THROUGH = (CistrackError, np.linalg.LinAlgError, FloatingPointError)
"""Errors of a stage that say the belief cannot be measured (the filter's failure, as when the filter
raises them itself): they reach the run as they are. Any other is the stage's own failure."""
_NUMBERS = (float, int, np.floating, np.integer, np.bool_)


class MetricStage:
    """Runs a run's ordered :class:`StepMetric` stages on each step event (see the module docstring).
    ``origins``: stage name -> the plugin that added it, named with the stage in its errors."""

    def __init__(self, stages: Iterable[StepMetric], origins: dict[str, str] | None = None) -> None:
        self.stages = order_metrics(stages)
        self.origins = dict(origins or {})

    def start(self, run: Any) -> None:
        for s in self.stages:
            self._call(s, "start", run)

    def measure(self, run: Any, step: Any, event: str) -> Any:
        """Compute every stage's metrics of ``step`` at ``event`` into ``step.metrics`` (left
        read-only); returns ``step``. A stage that raises (but for :data:`_PASS_THROUGH`), returns
        anything but a dict of str -> number, or a key already present raises PluginError naming it."""
        found: dict[str, float] = dict(step.metrics)
        for s in self.stages:
            step.metrics = ReadOnlyMetrics(found)
            out = self._call(s, "compute", run, step, event)
            if out is not None and not (isinstance(out, dict) and not out):
                self._check(s, out, found)
                found.update(out)
        step.metrics = ReadOnlyMetrics(found)
        return step

    def _error(self, stage: StepMetric, what: str) -> PluginError:
        """PluginError ``metric stage 'name'<what>``, with the plugin that added the stage."""
        origin = self.origins.get(stage.name)
        return PluginError(f"metric stage {stage.name!r}{what}" + (f" (a stage of {origin})" if origin else ""))

    def _call(self, stage: StepMetric, method: str, *args: Any) -> Any:
        try:
            return getattr(stage, method)(*args)
        except _PASS_THROUGH:
            raise
        except BaseException as exc:  # GeneratorExit, a KeyboardInterrupt no signal raised too (probe I1)
            if not plugin_fault(exc):
                raise
            hint = (" (the step's belief is read-only: a stage measures it and must not modify it)"
                    if isinstance(exc, ValueError) and "read-only" in str(exc) else "")
            raise self._error(stage, f": {method}() raised {exception_text(exc)}{hint}") from exc

    def _check(self, stage: StepMetric, out: Any, found: dict[str, float]) -> None:
        """Refuse (PluginError) a result that is not a dict of str -> number, or that writes a key
        an earlier stage wrote (a programming error of a stage, not a failure of the filter)."""
        if not isinstance(out, dict):
            raise self._error(stage, f": compute() must return a dict of str -> float, got {type(out).__name__}")
        for k, v in out.items():
            if not isinstance(k, str):
                raise self._error(stage, f": key {k!r} ({type(k).__name__}) is not a str: metric names are str")
            if not (isinstance(v, _NUMBERS) or (isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind in "biuf")):
                shown = repr(v) if len(repr(v)) <= 40 else repr(v)[:37] + "..."
                raise self._error(stage, f": key {k!r} = {shown} is not a number")
        again = found.keys() & out.keys()
        if again:
            raise self._error(stage, f" writes {', '.join(sorted(again))}, which an earlier stage wrote")

    def timed(self, run: Any, step: Any, event: str) -> Any:
        """:meth:`measure`, with its time in ``step.timings["metrics"]`` (seconds)."""
        tm = time.perf_counter()
        self.measure(run, step, event)
        step.timings["metrics"] = time.perf_counter() - tm
        return step
