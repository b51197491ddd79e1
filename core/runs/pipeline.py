"""One run: truth -> measurements -> IOD -> filter steps, observed through lifecycle hooks.

    truth = dynamics.propagate(x0, grid)              (the truth model may differ from the filter's)
    passes = sensor.passes(grid, truth)
    times = schedule.plan(passes, duration, rng)      measurements = sensor.simulate(truth, times, rng)
    cloud = iod.estimate(measurements, sensor, rng)
    filter.initialize(cloud); for each later measurement: filter.predict(t); filter.update(z)

Random streams: one ``numpy.random.SeedSequence(seed)`` is split into independent streams for
the measurement noise, the schedule, the IOD and the filter, so that for one scenario and seed
every filter and IOD variant sees the same measurements.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pluggy

from cistrack import units
from cistrack.evaluation.custody import CustodyMetric, Verdict
from cistrack.evaluation.metric_stage import MetricStage
from cistrack.evaluation.verdicts import final_verdict
from cistrack.scenario.limits import check_seed
from cistrack.interrupts import interrupt_text, plugin_fault, raise_pending
from cistrack.errors import CistrackError, ConfigError, FilterError, PluginError, exception_text
from cistrack.interfaces.component import component_name
from cistrack.interfaces.filter import DIAGNOSTICS_RULE, bad_diagnostic
from cistrack.model.measurement import StackedMeasurement
from cistrack.plugin.registry import Registry, default_registry
from cistrack.runs.compile_clock import CompileClock
from cistrack.runs.dynamics_contract import checked_dynamics
from cistrack.runs.iod_message import iod_message
from cistrack.runs.maneuver_watch import ManeuverMetric, ManeuverWatch
from cistrack.runs.observers import (builtin_metrics, finish_observers, interrupted_late, make_plugin_manager,
                                     metric_stage, notify, run_observers)
from cistrack.runs.run_context import RunContext, RunOptions, Step
from cistrack.runs.run_id import scenario_run_id
from cistrack.runs.run_inputs import (estimate_iod, in_table, plan_measurement_times, read_scenario_observations,
                                      simulate_measurements)
from cistrack.evaluation.run_summary import RunSummary, summarize
from cistrack.scenario.loading import Scenario
from cistrack.threads import library_thread_limit
from cistrack.results.step_table import RowCollector, is_table_step
from cistrack.runs.truth import Truth

__all__ = ["run_scenario", "RunResult", "RunOptions", "RunContext", "Step", "make_plugin_manager", "prepare_run"]


@dataclass
class RunResult:
    """What :func:`run_scenario` returns: the context, the table rows (one per step, as written
    to ``steps.parquet``, see :func:`cistrack.results.step_table.step_row`), the typed summary and, with
    ``keep_steps``, the steps themselves."""

    context: RunContext
    rows: list[dict[str, Any]]
    summary: RunSummary
    steps: list[Step] = field(default_factory=list)


def _streams(seed: int) -> dict[str, np.random.Generator]:
    names = ("measurements", "schedule", "iod", "filter", "maneuvers")  # spawn keys by index: adding one changes none
    children = np.random.SeedSequence(seed).spawn(len(names))
    return {n: np.random.default_rng(c) for n, c in zip(names, children)}


def prepare_run(scenario: Scenario, seed: int | None = None, registry: Registry | None = None,
                run_id: str | None = None, output_dir: Path | None = None, log=None) -> tuple[RunContext, dict]:
    """Build components, truth, passes, measurements and the IOD cloud (everything before the
    first filter step). Returns the context and the random streams."""
    reg = registry or default_registry()
    seed = scenario.seed if seed is None else check_seed(seed, "seed")
    rngs = _streams(seed)
    say = log or (lambda msg: None)
    dynamics = checked_dynamics(scenario.build("dynamics", reg), reg)  # a third party's: checked at each call
    sensor = scenario.build("sensor", reg)
    schedule = scenario.build("schedule", reg)
    iod = scenario.build("iod", reg)
    filt = scenario.build("filter", reg)
    truth_dyn = checked_dynamics(scenario.truth_dynamics.build(reg), reg) if scenario.truth_dynamics else dynamics
    duration = scenario.duration

    if scenario.measurements_file is not None:  # real observations, through a registered reader
        measurements, sensor = read_scenario_observations(scenario, sensor, reg, say)
        grid = np.zeros(0)
        grid_states = np.zeros((0, 6))
        truth, truth_impulses = None, []
        passes = []
    else:
        initial = scenario.initial_truth(reg)
        _compile_ahead(dynamics, initial)
        # with log None (--quiet) a burn the run leaves out is still said, as a warning
        truth_dyn, truth_impulses = _fly_truth_plan(scenario, reg, truth_dyn, initial, log)
        truth = Truth(truth_dyn, initial, t_end=duration)
        n_grid = int(np.ceil(duration / float(units.hours_to_tu(scenario.truth_grid_minutes / 60.0)))) + 1
        grid = np.linspace(0.0, duration, n_grid)
        say(f"propagating the truth over {scenario.duration_days:g} days ({n_grid} grid points)")
        try:
            grid_states = truth.states_at(grid)
        except ConfigError as exc:
            raise ConfigError(f"{scenario.source}: {exc}") from None
        if schedule is None:
            raise ConfigError(f"{scenario.source}: simulated measurements need a [schedule] table")
        if scenario.observers:  # several observers: each plans and measures, one network fuses them
            from cistrack.runs.network import simulate_network
            seen = simulate_network(scenario, reg, truth, grid, grid_states, rngs, say)
            measurements, sensor, passes = seen.measurements, seen.sensor, seen.passes
        else:
            measurements, passes = _one_sensor(scenario, (sensor, schedule, reg), truth, (grid, grid_states), rngs, say)
    if scenario.observers and truth is not None:
        from cistrack.runs.network import iod_input
        iod_measurements, iod_sensor = iod_input(scenario, measurements, sensor)
        say(f"the IOD works from observer {scenario.iod_observer!r} ({len(iod_measurements)} measurements)")
    else:
        from cistrack.astro.site_network import one_per_time
        iod_measurements, iod_sensor = one_per_time(measurements, sensor, say)  # the IOD: one site per time
    cloud = estimate_iod(scenario, iod, iod_measurements, iod_sensor, rngs["iod"], truth is not None, reg)
    say(iod_message(scenario.components["iod"].name, cloud, len(measurements)))
    rid = run_id or scenario_run_id(scenario, seed)
    ctx = RunContext(run_id=rid, scenario=scenario, seed=seed, epoch=scenario.epoch, dynamics=dynamics,
                     sensor=sensor, schedule=schedule, iod=iod, filter=filt, truth_times=grid,
                     truth_states=grid_states, passes=passes, measurements=measurements, iod_cloud=cloud,
                     output_dir=output_dir, truth_dynamics=truth_dyn, truth=truth, truth_impulses=truth_impulses,
                     registry=reg)
    return ctx, rngs


def _fly_truth_plan(scenario: Scenario, reg: Registry, truth_dyn, initial, say):
    """The truth's dynamics flying the scenario's ``[truth.maneuvers]`` plan (the truth's burns
    only), and its impulses (:func:`cistrack.propagation.impulses.fly_plan`); a failing plan is
    named with its distribution."""
    from cistrack.propagation.impulses import fly_plan

    plan = scenario.truth_maneuvers.build(reg) if scenario.truth_maneuvers else None
    who = reg.describe("maneuver-plan", component_name(plan)) if plan is not None else None
    return fly_plan(plan, truth_dyn, initial, 0, scenario.duration, say, f"{scenario.source}: [truth.maneuvers]", who)


def _one_sensor(scenario, components, truth, grids, rngs, say):
    """(measurements, passes) of the scenario's one sensor: its passes of the truth (a pass in
    progress at t = 0 skipped), the schedule's times in them, noisy measurements at those times.
    ``components``: (sensor, schedule, registry); ``grids``: the truth's (times, states)."""
    (sensor, schedule, reg), (grid, grid_states) = components, grids
    with in_table(scenario, scenario.components["sensor"].where):  # its orbit's or site's own error names the table
        passes = sensor.passes(grid, grid_states)
    skipped = ""
    if passes and passes[0].start <= grid[0] + 1e-12:
        # A pass already in progress at t = 0 is cut short; the target is acquired at its
        # first rise, so tasking (and the IOD's "first pass") starts with the next pass.
        say(f"skipping the pass in progress at t = 0 (visible for its first {_pass_length(passes[0].end - grid[0])} only)")
        skipped = (f"; the pass in progress at t = 0 ({_pass_length(passes[0].end - grid[0])}"
                   f"{', the whole run: the target does not set within it' if passes[0].end >= grid[-1] - 1e-12 else ''})"
                   " is never tasked, as the target is acquired at its first rise")
        passes = passes[1:]
    times = plan_measurement_times(scenario, schedule, passes, rngs["schedule"])
    if times.size == 0:
        raise ConfigError(f"{scenario.source}: the schedule produced no measurement times "
                          f"({len(passes)} visibility passes in {scenario.duration_days:g} days{skipped})")
    say(f"{len(passes)} passes, {times.size} measurements scheduled")
    return simulate_measurements(sensor, truth.states_at(times), times, rngs["measurements"], reg), passes


def _pass_length(tu: float) -> str:
    """A pass's length in words: hours, or seconds under six minutes (a run of 1e-6 days had said
    '0.0 h, the whole run: the target never sets')."""
    hours = float(units.tu_to_hours(tu))
    return f"{hours:.1f} h" if hours >= 0.1 else f"{hours * 3600.0:.3g} s"


def _compile_ahead(dynamics, state) -> None:
    """On a first run (kernel not in the cache) start compiling the filter's lockstep propagation
    kernel in a second process while the truth and the IOD run here (see
    :mod:`cistrack.propagation.background_compile`); same kernels, same numbers."""
    from cistrack.propagation.compiled import CompiledDynamics

    if isinstance(dynamics, CompiledDynamics):
        from cistrack.propagation import background_compile

        background_compile.start(dynamics, np.asarray(state, dtype=float).reshape(-1)[:dynamics.dim])


def run_scenario(scenario: Scenario, *, options: RunOptions | None = None, **keywords: Any) -> RunResult:
    """Run one scenario end to end and return its metrics and summary.

    ``options`` (a :class:`RunOptions`), each field of which may also be given as a keyword
    (a keyword wins): ``seed``, ``registry``, ``observers``, ``output_dir``, ``progress``,
    ``run_id``, ``keep_steps``, ``log``, ``blas_threads``, ``rows_per_part``.

    ``observers`` receive the lifecycle hooks (and may add metric stages through
    ``cistrack_metric_stages``); when ``output_dir`` is given a
    :class:`cistrack.results.store.ResultsWriter` writing there is added. ``progress`` shows a progress
    bar on stderr; ``log`` (a callable taking a string) receives stage messages.

    ``blas_threads`` limits BLAS threads during the run (default 1): the linear algebra of a run
    is many small matrices, for which multi-threaded BLAS is slower (measured 150x on 6x6 solves
    on a busy 2-core machine); the parallel work is the numba propagation. None: BLAS gets the
    run's thread limit. The whole run, plugins included, runs within :func:`cistrack.threads.num_threads`
    (``$CISTRACK_NUM_THREADS``) OpenMP and BLAS threads (:func:`cistrack.threads.library_thread_limit`).

    ``rows_per_part``: steps per results part file in ``output_dir`` (default
    :data:`cistrack.results.part_files.ROWS_PER_PART`; a part is also written every
    :data:`~cistrack.results.part_files.SECONDS_PER_PART` seconds); the merged tables do not depend on it.
    """
    opts = (options or RunOptions()).with_keywords(keywords)
    with library_thread_limit(blas=opts.blas_threads):  # plugins' OpenMP and BLAS pools included
        return _run(scenario, opts)


def _events(scenario: Scenario, ctx: RunContext) -> list[tuple[float, tuple[int, ...]]]:
    """The filter's steps after the IOD epoch, in time order: (t TU, the indices of the
    measurements taken at t, or () for a prediction-only step). Measurements sharing a time tag
    (several sites at once) make one step."""
    ms = ctx.measurements
    events: list = [(float(ms.times[g[0]]), tuple(int(i) for i in g)) for g in ms.time_groups()
                    if ms.times[g[0]] > ctx.iod_cloud.epoch + 1e-12]
    t_last = ctx.iod_cloud.epoch
    if scenario.predict_every_hours > 0:
        dt = float(units.hours_to_tu(scenario.predict_every_hours))
        meas_t = np.sort([e[0] for e in events]) if events else np.zeros(0)
        ts = np.arange(t_last + dt, scenario.duration, dt)
        if meas_t.size:  # distance to the nearest measurement time, in O(log n) per prediction
            k = np.searchsorted(meas_t, ts)
            before, after = meas_t[np.clip(k - 1, 0, None)], meas_t[np.minimum(k, meas_t.size - 1)]
            near = np.minimum(np.abs(before - ts), np.abs(after - ts))
            ts = ts[near > 1e-6]
        events += [(float(t), ()) for t in ts]
    if scenario.end_with_prediction and scenario.duration > max([t_last] + [e[0] for e in events]) + 1e-9:
        events.append((scenario.duration, ()))
    events.sort(key=lambda e: (e[0], e[1][:1] or (-1,)))
    return events


def _step(ctx: RunContext, index: int, t: float, kind: str, belief, group: tuple = ()) -> Step:
    return Step(index=index, t=t, utc=units.format_utc(units.tu_to_utc(ctx.epoch, t)), kind=kind,
                belief=belief, truth=ctx.truth_at(t), measurement=group[0] if group else None,
                group=tuple(group))


def _run(scenario: Scenario, opts: RunOptions) -> RunResult:
    """:func:`_run_timed` with numba's compilation timed apart (:class:`CompileClock`)."""
    clock = CompileClock()
    with clock:
        return _run_timed(scenario, opts, clock)


def _run_timed(scenario: Scenario, opts: RunOptions, clock: CompileClock) -> RunResult:
    """Build once, then one way through: truth, measurements, IOD, filter steps. Each step's
    metrics come from the metric stage (:mod:`cistrack.evaluation.metric_stage`); everything else
    (rows, results files, progress, recordings) is an observer of the hooks."""
    reg = opts.registry or default_registry()
    custody = CustodyMetric(scenario.custody)
    collector = RowCollector(keep_steps=opts.keep_steps)
    pm = make_plugin_manager(run_observers([custody, collector], opts, reg), reg)
    watch = _maneuver_watch(scenario, reg)
    stages = builtin_metrics(custody) + ([ManeuverMetric(watch)] if watch is not None else [])
    metrics = metric_stage(pm, scenario, stages)  # a bad stage is refused before any work
    t_start = time.perf_counter()
    ctx, rngs = prepare_run(scenario, opts.seed, reg, opts.run_id, opts.output_dir, opts.log)
    if watch is not None:
        watch.rng, watch.filter_rng, watch.say = rngs["maneuvers"], rngs["filter"], opts.log or (lambda m: None)
        ctx.maneuvers = watch
    t_prepare = time.perf_counter() - t_start - clock.seconds
    events = _events(scenario, ctx)
    if watch is not None and scenario.maneuvers.asked:  # the default watch of a short run is no one's choice
        _say_if_detector_idle(watch, events, opts.log)
    if ctx.truth is not None:  # the third wave of truth times (see cistrack.runs.truth): evaluations
        ctx.truth.states_at([ctx.iod_cloud.epoch] + [e[0] for e in events])
    if opts.progress:
        from cistrack.runs.progress import ProgressBar
        pm.register(ProgressBar(ctx.run_id, len(events), custody), name="observer-progress-ProgressBar")
    pending = [_initial_step(ctx, rngs["filter"])]  # handed on, not kept here: its particles go with its hooks
    status, failure, abort = _guarded(pm, ctx, collector, lambda: _steps(ctx, pm, metrics, events, pending))
    times, summary = (t_start, t_prepare, clock), None
    try:  # a Ctrl-C while the run is judged or its burns estimated is recorded like one between steps
        summary = _judged(ctx, custody, collector, (status, failure), times)
        if watch is not None:
            summary.maneuvers = watch.records(ctx)
    except KeyboardInterrupt as exc:
        abort = abort or exc
        summary = (_judged(ctx, custody, collector, ("interrupted", interrupt_text(exc)), times) if summary is None
                   else interrupted_late(summary, exc))
    summary = finish_observers(pm, ctx, summary)  # an interrupt there is recorded, then raised again
    if opts.output_dir is not None and opts.residual_figure:  # drawn from the merged steps.parquet: after the results writer
        from cistrack.runs.residual_figure import write_run_residual_figure
        write_run_residual_figure(ctx, opts.output_dir, summary.status)
    if abort is not None:
        raise abort
    return RunResult(ctx, collector.rows, summary, collector.steps)


def _judged(ctx: RunContext, custody: CustodyMetric, collector: RowCollector, ended: tuple[str, str],
            times: tuple[float, float, CompileClock]) -> RunSummary:
    """The run's summary: its verdict, judged at the end when it ``ended`` (status, failure) finished
    or filter-failed, else :func:`_unfinished_verdict`; ``times``: its start (perf_counter s), its
    preparation (s) and its compile clock."""
    status, failure = ended
    t_start, t_prepare, clock = times
    verdict = final_verdict(custody.verdict, collector.rows, _judging_rule(ctx.scenario.custody, ctx.measurements),
                            ctx.truth is not None,
                            custody.earth_distance_km, custody.truth_earth_distance_km) \
        if status in ("finished", "filter-failed") else _unfinished_verdict(custody.verdict, status)
    return summarize(ctx, collector.rows, verdict, status, failure,
                     time.perf_counter() - t_start - clock.seconds, t_prepare, clock.seconds)


def _unfinished_verdict(custody: Verdict, status: str) -> Verdict:
    """The verdict of a run that did not finish (failed, interrupted): custody lost before it
    stopped, else "none" (a "kept" custody was never judged at the end)."""
    if custody.kind != "kept":
        return custody
    return Verdict("none", f"the run did not finish ({status}); it was not judged")


def _initial_step(ctx: RunContext, rng: np.random.Generator) -> Step:
    """The filter initialised with the IOD cloud, as step 0 (its time in ``timings["initialize"]``)."""
    t0 = time.perf_counter()
    try:
        ctx.filter.initialize(ctx.iod_cloud, ctx.dynamics, ctx.sensor, rng)
        belief = ctx.filter.belief
    except (CistrackError, MemoryError):
        raise
    except BaseException as exc:  # a plugin's own bug (its filter's, its clusterer's): named, not a traceback
        if not plugin_fault(exc):
            raise
        raise FilterError(f"{_filter_who(ctx)} failed while starting from the IOD's cloud: "
                          f"{exception_text(exc)}") from exc
    step0 = _step(ctx, 0, ctx.iod_cloud.epoch, "initial", _check_belief(ctx, belief, ctx.iod_cloud.epoch, 0,
                                                                          "initialize"))
    step0.timings["initialize"] = time.perf_counter() - t0
    return step0


def _check_belief(ctx: RunContext, belief, t: float, k: int, after: str):
    """``belief``, the filter's (of ``ctx``) after ``after`` ("initialize", "predict", "update") at step ``k``,
    time ``t`` (TU); a FilterError naming the filter and the step unless it is at ``t`` (to 1e-9 TU
    relative) with a finite mean and covariance: metrics would compare a stale belief with the
    truth at a later time, or carry NaN as if it were a track."""
    who, days = _filter_who(ctx), float(units.tu_to_days(t))
    try:
        epoch, gm = float(belief.epoch), belief.mixture
        finite = bool(np.isfinite(gm.means).all() and np.isfinite(gm.covariances).all())
    except (AttributeError, TypeError, ValueError) as exc:
        raise FilterError(f"{who}: its belief after {after} at step {k} is not a cistrack Belief with a time and "
                          f"a GaussianMixture ({exception_text(exc)})") from None
    if not abs(epoch - t) <= 1e-9 * max(1.0, abs(t)):
        shown = _two_times(float(units.tu_to_days(epoch)), days)
        raise FilterError(f"{who}: belief epoch {shown[0]} d after {after} to {shown[1]} d (step {k}); a filter's "
                          "belief must be at the time it was moved to")
    if not finite:
        raise FilterError(f"{who}: the belief's mean or covariance is NaN or infinite after {after} at step {k} "
                          f"(t = {days:.3f} d)")
    return belief


def _filter_who(ctx: RunContext) -> str:
    """The run's filter as messages name it: ``filter 'pgm'``, with its distribution when a third
    party's (``filter 'h-mine' (hplug 0.1)``)."""
    name = component_name(ctx.filter)
    return ctx.registry.describe("filter", name) if ctx.registry is not None else f"filter '{name}'"


def _filter_call(ctx: RunContext, method: str, k: int, t: float, call: Callable[..., Any], *args: Any) -> Any:
    """``call(*args)``, the filter's ``method`` at step ``k``, time ``t`` (TU). The filter's own
    exception (a bug of a third party's filter: KeyError, ValueError, ``sys.exit`` ...) becomes a
    FilterError naming the filter, the method and the step, so that the run ends "filter-failed"
    (``cistrack_run_failed`` is told); cistrack's errors, numerical failures (LinAlgError,
    FloatingPointError), MemoryError and interrupts pass as they are."""
    try:
        return call(*args)
    except (CistrackError, np.linalg.LinAlgError, FloatingPointError, MemoryError):
        raise
    except BaseException as exc:  # GeneratorExit, or a KeyboardInterrupt no signal raised, too (probe I1)
        if not plugin_fault(exc):
            raise
        raise FilterError(f"{_filter_who(ctx)} raised {exception_text(exc)} in {method} at step {k} "
                          f"(t = {float(units.tu_to_days(t)):.3f} d)") from exc


def _two_times(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` (days) with 3 decimals, or with as many digits as tell them apart."""
    digits = 3
    while f"{a:.{digits}f}" == f"{b:.{digits}f}" and digits < 15:
        digits += 2
    return f"{a:.{digits}f}", f"{b:.{digits}f}"


def _guarded(pm: pluggy.PluginManager, ctx: RunContext, collector: RowCollector,
             steps: Callable[[], None]) -> tuple[str, str, BaseException | None]:
    """Run ``steps``; (status, failure, the interrupt to raise again once the run is finished)."""
    try:
        steps()
    except PluginError as exc:  # a plugin's hook or metric stage, named in the message
        return "failed", str(exc), None
    except (CistrackError, np.linalg.LinAlgError, FloatingPointError) as exc:
        failure = f"{type(exc).__name__}: {exc}"
        try:
            notify(pm, "cistrack_run_failed", run=ctx, step_index=len(collector.rows), error=failure)
        except PluginError as obs_exc:  # an observer failing on the failure: still finish the run
            return "failed", f"{failure}; then {obs_exc}", None
        return "filter-failed", failure, None
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM/SIGHUP through the CLI's handler
        return "interrupted", interrupt_text(exc), exc
    except BaseException as exc:  # a results writer (full disk), a component's sys.exit or GeneratorExit, anything
        return "failed", exception_text(exc), None
    return "finished", "", None


def _steps(ctx: RunContext, pm: pluggy.PluginManager, metrics: MetricStage, events: list, pending: list) -> None:
    """The run from its start: the metric stages and observers told, the initial step (taken from
    ``pending``), then one step per event."""
    metrics.start(ctx)
    notify(pm, "cistrack_run_started", run=ctx)
    _observe(ctx, pm, metrics, pending.pop(), "predicted")
    for k, (t, group) in enumerate(events, start=1):
        raise_pending()  # a Ctrl-C lost inside the compiler's ctypes callback stops the run here
        _event(ctx, pm, metrics, k, t, group)  # no step outlives its call: its belief is free before the next predict
    raise_pending()


def _event(ctx: RunContext, pm: pluggy.PluginManager, metrics: MetricStage, k: int, t: float, group: tuple) -> None:
    """Step ``k``: predict to ``t``; with measurements (indices ``group``) hand on the prior, then update."""
    filt = ctx.filter
    tp = time.perf_counter()
    _filter_call(ctx, "predict", k, t, filt.predict, t)
    prior = _filter_call(ctx, "belief", k, t, getattr, filt, "belief")  # timed with the prediction (forming it is part of it)
    t_pred = time.perf_counter() - tp
    _check_belief(ctx, prior, t, k, "predict")
    if not group:
        step = _step(ctx, k, t, "predict", prior)
        step.timings["predict"] = t_pred
        _observe(ctx, pm, metrics, step, "predicted")
        return
    ms = tuple(_angles(ctx.measurements[i]) for i in group)
    _observe(ctx, pm, metrics, _step(ctx, k, t, "update", prior, ms), "predicted")
    if ctx.maneuvers is not None:
        _watch(ctx, k, t, prior, ms)
    del prior  # the prior's particles need not outlive its hook
    tu = time.perf_counter()
    for m in ((StackedMeasurement(ms),) if len(ms) > 1 and filt.stacked_updates else ms):
        _filter_call(ctx, "update", k, t, filt.update, m)  # several sites at one time: one stacked update, or one after another
    posterior = _filter_call(ctx, "belief", k, t, getattr, filt, "belief")
    step = _step(ctx, k, t, "update", _check_belief(ctx, posterior, t, k, "update"), ms)
    if ctx.maneuvers is not None:
        ctx.maneuvers.after_update(t, step.belief)
    step.timings.update({"predict": t_pred, "update": time.perf_counter() - tu})
    _observe(ctx, pm, metrics, step, "updated")


def _observe(ctx: RunContext, pm: pluggy.PluginManager, metrics: MetricStage, step: Step, event: str) -> None:
    """The metric stage, then the observers' hook of ``event``. A table step (see
    :func:`~cistrack.results.step_table.is_table_step`) also gets the filter's diagnostics and the
    metrics' time; the prior of an update only what the stages compute for it. Stages and observers
    get the belief with read-only arrays: the filter's state is safe from them."""
    step.belief = read_only_belief(step.belief)
    if is_table_step(event, step):
        step.diagnostics = _diagnostics(ctx, step)
        metrics.timed(ctx, step, event)
    else:
        metrics.measure(ctx, step, event)
    notify(pm, "cistrack_step_updated" if event == "updated" else "cistrack_step_predicted", run=ctx, step=step)


def _diagnostics(ctx: RunContext, step: Step) -> dict:
    """The diagnostics of the run's filter after ``step``; a FilterError naming the filter, the key, the value
    and the step when one of the documented ones is not a finite number >= 0 (the verdict reads
    them, and the table would hold the NaN or negative count as if it were measured)."""
    diag = _filter_call(ctx, "diagnostics", step.index, step.t, lambda: dict(ctx.filter.diagnostics))
    bad = bad_diagnostic(diag)
    if bad is not None:
        after = {"initial": "initialize"}.get(step.kind, step.kind)
        raise FilterError(f"{_filter_who(ctx)}: diagnostic {bad[0]!r} = {bad[1]!r} after {after} at step "
                          f"{step.index} (t = {float(units.tu_to_days(step.t)):.3f} d); {DIAGNOSTICS_RULE}")
    return diag


def _judging_rule(rule, measurements):
    """``rule`` for the run's measurements: its collapse threshold scaled to their finest angle
    sigma (:meth:`cistrack.evaluation.custody.CustodyRule.for_angle_sigma`)."""
    names = tuple(getattr(measurements, "names", ()))
    cols = [j for j, n in enumerate(names) if "range" not in str(n)]
    sig = np.asarray(getattr(measurements, "sigmas", np.empty((0, 0))), dtype=float)
    if not cols or sig.ndim != 2 or sig.shape[0] == 0:
        return rule
    finest = float(np.nanmin(sig[:, cols])) / units.ARCSEC_RAD
    return rule.for_angle_sigma(finest)


def read_only_belief(belief):
    """``belief`` with read-only views of its arrays (:meth:`Belief.read_only`; as it is when it
    has no such method)."""
    ro = getattr(belief, "read_only", None)
    return ro() if callable(ro) else belief


def _maneuver_watch(scenario: Scenario, reg: Registry) -> ManeuverWatch | None:
    """The run's :class:`ManeuverWatch` from ``[maneuvers]`` (None without a detector)."""
    settings = scenario.maneuvers
    if settings.detector is None:
        return None
    response = settings.response.build(reg) if settings.response is not None else None
    detector = settings.detector.build(reg)
    names = (reg.describe("maneuver-detector", component_name(detector)),
             reg.describe("maneuver-response", component_name(response)) if response is not None else "")
    return ManeuverWatch(detector, response, settings.estimate, names=names)


def _say_if_detector_idle(watch: ManeuverWatch, events: list, say) -> None:
    """Say so when the detector's ``warmup`` (updates it only watches) covers every update of
    the run: such a run can detect nothing."""
    warmup = getattr(watch.detector, "warmup", 0)
    n_updates = sum(1 for _, group in events if group)
    if say is not None and isinstance(warmup, int) and warmup >= n_updates:
        say(f"maneuver detector {component_name(watch.detector)}: warmup = {warmup} covers all {n_updates} "
            "updates of this run; it can detect nothing (lower [maneuvers.detector] warmup)")


def _watch(ctx: RunContext, k: int, t: float, prior, ms: tuple) -> None:
    """The maneuver watch's look at the measurements ``ms`` of step ``k`` at ``t`` under ``prior``; when its response
    hands back a cloud, the filter starts again from it (before it takes ``ms``)."""
    cloud = ctx.maneuvers.before_update(ctx, t, prior, ms, k)
    if cloud is not None:
        ctx.maneuvers.say(f"maneuver detected at {units.tu_to_days(t):.3f} d; the filter starts again from the "
                f"response's cloud ({len(cloud)} particles)")
        _filter_call(ctx, "initialize", k, t, ctx.filter.initialize, cloud, ctx.dynamics, ctx.sensor,
                     ctx.maneuvers.filter_rng)


def _angles(m):
    return m.angles_only() if "range" in m.names else m
