"""Running the conformance checks: per component, per registered name, or under pytest."""
from __future__ import annotations

import time
from typing import Any, Callable, Iterable, Iterator

from cistrack.errors import ParameterError, UnknownComponentError
from cistrack.interrupts import plugin_fault
from cistrack.interfaces import KINDS
from cistrack.interfaces.orbit import ReferenceOrbit
from cistrack.testing.check_support import describe_exception, fresh
from cistrack.testing.checks_clustering import CLUSTERING_CHECKS
from cistrack.testing.checks_dynamics import DYNAMICS_CHECKS
from cistrack.testing.checks_filter import FILTER_CHECKS
from cistrack.testing.checks_iod import IOD_CHECKS
from cistrack.testing.checks_maneuvers import MANEUVER_PLAN_CHECKS, MANEUVER_RESPONSE_CHECKS
from cistrack.testing.checks_maneuver_detectors import MANEUVER_DETECTOR_CHECKS
from cistrack.testing.checks_orbit import ORBIT_CHECKS
from cistrack.testing.checks_pgm_steps import PGM_STEP_CHECKS
from cistrack.testing.checks_params import PARAMETER_CHECKS, check_parameters_declared
from cistrack.testing.checks_exporter import EXPORTER_CHECKS
from cistrack.testing.checks_range_prior import RANGE_PRIOR_CHECKS
from cistrack.testing.checks_reader import READER_CHECKS
from cistrack.testing.checks_recorder import RECORDER_CHECKS, lifecycle_hooks
from cistrack.testing.checks_schedule import SCHEDULE_CHECKS
from cistrack.testing.checks_sensor import SENSOR_CHECKS
from cistrack.testing.check_results import CheckResult, ConformanceError, ConformanceReport

__all__ = ["BoundCheck", "infer_kind", "iter_checks", "check_plugin", "check_registered",
           "parametrize_with_checks", "KIND_CHECKS"]

KIND_CHECKS: dict[str, list[tuple[str, Callable[[Any], None]]]] = {
    "dynamics": DYNAMICS_CHECKS,
    "sensor": SENSOR_CHECKS,
    "schedule": SCHEDULE_CHECKS,
    "iod": IOD_CHECKS,
    "clustering": CLUSTERING_CHECKS,
    "filter": FILTER_CHECKS,
    "orbit": ORBIT_CHECKS,
    "recorder": RECORDER_CHECKS,
    "reader": READER_CHECKS,
    "exporter": EXPORTER_CHECKS,
    "range-prior": RANGE_PRIOR_CHECKS,
    "maneuver-detector": MANEUVER_DETECTOR_CHECKS,
    "maneuver-plan": MANEUVER_PLAN_CHECKS,
    "maneuver-response": MANEUVER_RESPONSE_CHECKS,
    **PGM_STEP_CHECKS,
}
"""The kind-specific checks, run after the parameter checks (which every class-based kind gets)."""

PYTHON_ADVICE = "if it needs settings, check an instance: check_plugin(Cls(...)) or check_registered(name, params={...})"
"""What a failure to construct a class with its defaults advises, from Python (the command line
gives its own: ``--param KEY=VALUE``)."""


def infer_kind(component: Any) -> str:
    """The registry kind of a component, class or reference orbit."""
    if isinstance(component, ReferenceOrbit):
        return "orbit"
    kind = getattr(component, "kind", "")
    if isinstance(kind, str) and kind in KINDS:
        return kind
    if lifecycle_hooks(component):
        return "recorder"
    raise ParameterError(f"cannot tell which kind of plugin {component!r} is: derive it from a "
                         f"cistrack.interfaces class or pass kind= (one of {', '.join(KINDS)})")


def label(component: Any) -> str:
    """A short name for messages and test ids: the name the class itself was registered under (not
    one it inherits from a registered parent), the orbit's name, or the class name."""
    if isinstance(component, ReferenceOrbit):
        return component.name
    cls = component if isinstance(component, type) else type(component)
    own = cls.__dict__.get("registry_name", "")
    return own if isinstance(own, str) and own else cls.__name__


class BoundCheck:
    """One check bound to a component. Call it with no argument (or with the component, as
    scikit-learn's ``parametrize_with_checks`` tests do); it raises :class:`ConformanceError`
    naming the check and why when the component fails.

    Each call works on a fresh instance: a class is built with its defaults, an instance is
    rebuilt from ``get_params()``, so checks do not see each other's state.
    """

    def __init__(self, name: str, func: Callable[[Any], None], component: Any, kind: str,
                 advice: str = PYTHON_ADVICE):
        self.name = name
        self.func = func
        self.component = component
        self.kind = kind
        self.advice = advice

    def __repr__(self) -> str:
        return f"<check {self.name} of {self.kind} {label(self.component)!r}>"

    def _instance(self, component: Any) -> Any:
        if self.kind == "orbit" or (self.kind == "recorder" and not callable(getattr(component, "get_params", None))
                                    and not isinstance(component, type)):
            return component
        try:
            return fresh(component)
        except BaseException as exc:  # GeneratorExit, a KeyboardInterrupt no signal raised too (probe I1)
            if not plugin_fault(exc):
                raise
            how = "with its default parameters" if isinstance(component, type) else "from get_params()"
            raise ConformanceError(f"check '{self.name}' failed for {self.kind} '{label(component)}': could not "
                                   f"construct it {how}: {describe_exception(exc)} ({self.advice})") from exc

    def __call__(self, component: Any = None) -> None:
        target = self.component if component is None else component
        instance = self._instance(target)
        try:
            self.func(instance)
        except ConformanceError as exc:
            raise ConformanceError(f"check '{self.name}' failed for {self.kind} '{label(target)}': {exc}") from None
        except BaseException as exc:  # sys.exit in a plugin fails its check; the others still run
            if not plugin_fault(exc):
                raise
            raise ConformanceError(f"check '{self.name}' failed for {self.kind} '{label(target)}': it raised "
                                   f"{describe_exception(exc)}") from exc


def _constructs_with_defaults(component: Any) -> None:
    """Building the component with no arguments works (the BoundCheck did it already)."""


def iter_checks(component: Any, kind: str | None = None, *,
                advice: str = PYTHON_ADVICE) -> Iterator[tuple[str, BoundCheck]]:
    """Yield ``(check_name, check)`` for every check that applies to ``component`` (a class, an
    instance, or a ReferenceOrbit). Each ``check`` is a :class:`BoundCheck`: call it to run it.
    ``advice``: what a class that cannot be built with its defaults is told to do."""
    kind = kind or infer_kind(component)
    if kind not in KIND_CHECKS:
        raise ParameterError(f"unknown plugin kind {kind!r}; kinds are: {', '.join(KINDS)}")
    checks: list[tuple[str, Callable[[Any], None]]] = []
    if kind != "orbit":
        cls = component if isinstance(component, type) else type(component)
        if isinstance(component, type):
            checks.append(("constructs_with_defaults", _constructs_with_defaults))
        if callable(getattr(cls, "get_params", None)):
            checks.extend(PARAMETER_CHECKS)
        else:
            checks.append(("parameters_declared", check_parameters_declared))
    checks.extend(KIND_CHECKS[kind])
    for name, func in checks:
        yield name, BoundCheck(name, func, component, kind, advice)


def _run(name: str, check: Callable[[], None]) -> CheckResult:
    t0 = time.perf_counter()
    try:
        check()
    except AssertionError as exc:
        return CheckResult(name, False, str(exc), time.perf_counter() - t0)
    return CheckResult(name, True, "", time.perf_counter() - t0)


def _run_all(component: Any, kind: str, on_result: Callable[[CheckResult], None] | None = None,
             advice: str = PYTHON_ADVICE) -> list[CheckResult]:
    """Every check's result, each also handed to ``on_result`` as soon as it is known; if the
    component cannot even be constructed, only that failure."""
    results = []
    for name, check in iter_checks(component, kind, advice=advice):
        results.append(_run(name, check))
        if on_result is not None:
            on_result(results[-1])
        if name == "constructs_with_defaults" and not results[-1].passed:
            break
    return results


def check_plugin(component_or_class: Any, kind: str | None = None) -> ConformanceReport:
    """Run every check on a component (class, instance or reference orbit).

    Returns a :class:`ConformanceReport` when all pass; otherwise raises
    :class:`ConformanceError` (an ``AssertionError``) whose message names each failing check and
    why, with the full results in ``.results``.
    """
    kind = kind or infer_kind(component_or_class)
    report = ConformanceReport(label(component_or_class), kind, _run_all(component_or_class, kind))
    if report.failures:
        lines = [f"{kind} '{report.component}' failed {len(report.failures)} of {len(report.results)} conformance checks:"]
        lines += [f"  - {r.message}" for r in report.failures]
        raise ConformanceError("\n".join(lines), report.results)
    return report


def check_registered(name: str, kind: str | None = None, registry: Any = None,
                     params: dict[str, Any] | None = None, *, on_result: Callable[[CheckResult], None] | None = None,
                     advice: str = PYTHON_ADVICE) -> list[CheckResult]:
    """Look ``name`` up in ``registry`` (default: the process-wide one) and run its checks.

    ``kind`` is needed only when ``name`` is registered under several kinds. ``params`` builds
    the component with those parameters instead of its defaults (for components such as a
    recorder that need, e.g., an output path). Returns one :class:`CheckResult` (name, passed,
    message, seconds) per check; it does not raise on failures. ``on_result`` receives each
    result as soon as its check ends (``cistrack plugins --check`` prints it then); ``advice``
    is what a component that cannot be built with its defaults is told to do.
    """
    if registry is None:
        from cistrack.plugin.registry import default_registry
        registry = default_registry()
    if kind is None:
        kinds = [k for k in registry.kinds() if (k, name) in registry]
        if not kinds:
            known = sorted({n for k in registry.kinds() for n in registry.names(k)})
            raise UnknownComponentError(f"no plugin named {name!r} is registered; registered names: {', '.join(known)}")
        if len(kinds) > 1:
            raise ParameterError(f"{name!r} is registered as several kinds ({', '.join(kinds)}); say which with kind=")
        kind = kinds[0]
    factory = registry.get(kind, name).factory
    if params or (not isinstance(factory, type) and callable(factory) and kind not in ("orbit", "recorder")):
        try:
            factory = registry.create(kind, name, **(params or {}))
        except BaseException as exc:  # GeneratorExit, a KeyboardInterrupt no signal raised too (probe I1)
            if not plugin_fault(exc):
                raise
            how = f"with {params}" if params else "with its default parameters"
            failed = CheckResult("constructs_with_defaults", False, f"could not construct {kind} '{name}' {how}: "
                                 f"{describe_exception(exc)} ({advice})")
            if on_result is not None:
                on_result(failed)
            return [failed]
    return _run_all(factory, kind, on_result, advice)


def parametrize_with_checks(components: Iterable[Any]):
    """A ``pytest.mark.parametrize`` decorator over (component, check) for every check of
    every component, with ids ``<name>-<check>``::

        @parametrize_with_checks([MyFilter, MyClusterer(n_clusters=3)])
        def test_conformance(component, check):
            check(component)
    """
    import pytest

    params, ids = [], []
    for comp in components:
        for name, check in iter_checks(comp):
            params.append((comp, check))
            ids.append(f"{label(comp)}-{name}")
    return pytest.mark.parametrize(("component", "check"), params, ids=ids)
