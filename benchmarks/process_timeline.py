"""Where the time of one ``cistrack`` process goes, from interpreter start to exit.

    .venv/bin/python benchmarks/process_timeline.py run example-1 --seed 1 --quiet --out /tmp/run1
    taskset -c 0,1 .venv/bin/python benchmarks/process_timeline.py run example-1 --quiet --out DIR

Runs the command line (the arguments are those of ``cistrack``) in this process and prints, per
stage, wall and CPU seconds (CPU: user + system of every thread of the process, so the
propagation's worker threads count): the interpreter's own start, importing numpy and
cistrack, building the registry, the scenario, importing numba, numba's one-time target-context
set-up (its implementation registries; it imports scipy.linalg for numba's BLAS bindings), the
truth (the first compiled kernel), the rest of the preparation (measurements, IOD), the filter
steps and writing the results; then each numba function loaded (from the kernel cache when it
is warm) with its load time. The stages are marked by wrapping cistrack functions from outside;
nothing in cistrack is changed. Run it twice: the first run of a fresh install compiles.
"""
from __future__ import annotations

import time

_T0 = time.perf_counter()
_C0 = time.process_time()  # the interpreter's start and site imports, before this script ran

import sys  # noqa: E402

_MARKS: list[tuple[str, float, float]] = []
_LOADS: list[tuple[str, float, float]] = []


def _mark(name: str) -> None:
    _MARKS.append((name, time.perf_counter() - _T0, time.process_time()))


def _count_numba_loads() -> None:
    """Record each numba dispatcher compile (a cache load when the cache is warm)."""
    import numba.core.dispatcher as dispatcher

    compile_ = dispatcher.Dispatcher.compile

    def timed(self, sig):
        w, c = time.perf_counter(), time.process_time()
        out = compile_(self, sig)
        _LOADS.append((self.py_func.__name__, time.perf_counter() - w, time.process_time() - c))
        return out

    dispatcher.Dispatcher.compile = timed


def _wrap(owner, name: str, before: str | None, after: str) -> None:
    func = getattr(owner, name)

    def wrapped(*a, **k):
        if before:
            _mark(before)
        out = func(*a, **k)
        _mark(after)
        return out

    setattr(owner, name, wrapped)


def main(argv: list[str]) -> int:
    import numpy  # noqa: F401

    _mark("import numpy")
    from cistrack.cli.main import main as cli_main
    import cistrack.propagation.compiled as compiled
    import cistrack.plugin.registry as registry
    import cistrack.runs.pipeline as run
    import cistrack.runs.compile_clock as compile_clock

    _mark("import cistrack (cli, run, registry)")
    _wrap(registry, "default_registry", None, "build the registry (import plugins)")
    _wrap(run, "prepare_run", "scenario, observers", "prepare: measurements, IOD")
    _wrap(run, "finish_observers", "filter steps", "finish: observers write results")
    dense = compiled.CompiledDynamics.dense_trajectory
    started = []

    def start_numba(before: str) -> None:
        """Import numba and set up its target context as stages of their own (once), the
        interval before them named ``before``; then count the numba functions loaded."""
        if started:
            return
        started.append(True)
        if "numba.core.dispatcher" not in sys.modules:
            _mark(before)
            import numba  # noqa: F401

            _mark("import numba")
            from numba.core.registry import cpu_target

            cpu_target.target_context.refresh()
            _mark("numba target context (registries, scipy.linalg)")
        _count_numba_loads()

    # the run's thread limit (cistrack.threads.library_thread_limit) is numba's first importer
    scenario_run = run.run_scenario

    def run_with_numba(*a, **k):
        start_numba("scenario")
        return scenario_run(*a, **k)

    run.run_scenario = run_with_numba
    clock_enter = compile_clock.CompileClock.__enter__

    def enter_clock(self):
        start_numba("scenario")
        return clock_enter(self)

    compile_clock.CompileClock.__enter__ = enter_clock

    def first_kernel(self, *a, **k):
        start_numba("prepare: components")
        out = dense(self, *a, **k)
        _mark("truth (dense kernel load + integration)")
        return out

    compiled.CompiledDynamics.dense_trajectory = first_kernel
    code = cli_main(argv)
    _mark("exit of main()")
    print(f"{'stage':<50}{'wall s':>8}{'cpu s':>8}", file=sys.stderr)
    print(f"{'interpreter start, site':<50}{'':>8}{_C0:8.3f}", file=sys.stderr)
    prev_w, prev_c = 0.0, _C0
    for name, w, c in _MARKS:
        print(f"{name:<50}{w - prev_w:8.3f}{c - prev_c:8.3f}", file=sys.stderr)
        prev_w, prev_c = w, c
    print(f"{'total (wall from script start; cpu from exec)':<50}{_MARKS[-1][1]:8.3f}{_MARKS[-1][2]:8.3f}",
          file=sys.stderr)
    if _LOADS:
        print("numba functions loaded (or compiled) on first call:", file=sys.stderr)
        for name, w, c in _LOADS:
            print(f"  {name:<48}{w:8.3f}{c:8.3f}", file=sys.stderr)
        print(f"  {'all of them':<48}{sum(x[1] for x in _LOADS):8.3f}{sum(x[2] for x in _LOADS):8.3f}",
              file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
