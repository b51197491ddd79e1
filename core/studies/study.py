"""Comparative studies: scenarios x filters x IOD variants x seeds through any Executor.

A study file (TOML)::

    name = "filter-comparison"
    description = "PGM vs UKF vs EnKF on paper Example 1, three IOD range models"
    scenarios = ["example-1"]                  # built-in names or paths relative to this file
    filters = ["pgm", "ukf", "enkf"]           # names, or tables {name = ..., label = ..., params}
    iod = ["noisy-range", "uniform-range"]     # the same; omit to keep each scenario's own
    seeds = [1, 2, 3]                          # or n_seeds = 10 (seeds 1..10), with first_seed = 500
                                               # seeds 500..509
    [overrides]                                # applied to every scenario first
    duration_days = 6.6

Each run is written to ``<out>/runs/<run id>/`` as it finishes (see :mod:`cistrack.results.store`);
running the study again runs only what is missing (reports: :mod:`cistrack.studies.report`). Runs are pure functions of (scenario, seed):
the same seed gives the same numbers under any executor.
"""
from __future__ import annotations

import concurrent.futures as cf
import copy
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cistrack.errors import CistrackError, ConfigError
from cistrack.studies.lost_runs import refuse_in_a_starting_worker
from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.fingerprint import scenario_fingerprint
from cistrack.studies.study_file import (_study_seeds, builtin_studies, load_study, recorded_settings, study_source)
from cistrack.studies.resume import run_state
from cistrack.scenario.limits import check_count, check_path_component
from cistrack.studies.workers import execute_run, init_worker, run_spec
from cistrack.runs.run_id import run_id


__all__ = ["RunSpec", "load_study", "plan_runs", "execute_run", "run_study", "close_dask_client",
           "builtin_studies", "make_executor"]


@dataclass(frozen=True)
class RunSpec:
    """One run of a study (plain data: sent to worker processes)."""

    run_id: str
    scenario: str          # absolute path of the scenario file
    seed: int
    overrides: dict
    out_dir: str
    scenario_name: str
    filter_label: str
    iod_label: str
    rerun_path: str | None = None
    fingerprint: str = ""  # of the resolved scenario and seed (cistrack.results.fingerprint)


def _label_and_table(item: Any, key: str, p: Path) -> tuple[str, dict | None]:
    if item is None:
        return "", None
    if isinstance(item, str):
        return check_path_component(item, f"{p}: entry of {key!r}"), {"name": item}
    if isinstance(item, dict) and "name" in item:
        t = dict(item)
        label = check_path_component(t.pop("label", t["name"]), f"{p}: entry of {key!r}: key 'label'")
        return label, t
    raise ConfigError(f"{p}: entries of {key!r} must be names or tables with a 'name' key, got {item!r}")


def plan_runs(path_or_name: str | Path, out_dir: str | Path | None = None,
              settings: list[str] | None = None, first_seed: int | None = None,
              n_seeds: int | None = None) -> tuple[dict, list[RunSpec], Path]:
    """Every run of a study, validated (each scenario variant is parsed before any run starts).

    ``first_seed``, ``n_seeds``: run these seeds instead of the study file's (see
    :func:`_study_seeds`); the runs go into the same study directory, named by their seed.

    ``settings``: ``--set TABLE.KEY=VALUE`` items (:mod:`cistrack.scenario.settings`) applied to every run
    after the study's own overrides and variants; the default directory then names their hash,
    so runs with other values are never mixed with these.
    """
    from cistrack.plugin.registry import default_registry
    from cistrack.scenario.loading import load_scenario
    from cistrack.scenario.settings import merge_settings, parse_settings

    data, p = load_study(path_or_name)
    recorded = recorded_settings(path_or_name)  # a study results directory: its own runs, in place
    if recorded is not None:
        settings = recorded if settings is None else settings
        out_dir = path_or_name if out_dir is None else out_dir
    name = check_path_component(data.get("name", p.stem), f"{p}: key 'name'")
    extra = parse_settings(settings)
    out = Path(out_dir) if out_dir else Path("studies_out") / (name + _settings_suffix(settings))
    seeds = _study_seeds(data, p, first_seed, n_seeds)
    filters = [_label_and_table(f, "filters", p) for f in (data.get("filters") or [None])]
    iods = [_label_and_table(f, "iod", p) for f in (data.get("iod") or [None])]
    reg = default_registry()
    specs: list[RunSpec] = []
    for sc in data["scenarios"]:
        sp = Path(sc)
        if not sp.is_absolute() and (p.parent / sp).exists():
            sp = p.parent / sp
        base = load_scenario(sp if sp.exists() else sc, reg)
        scen_path = str(Path(base.source).resolve())
        for flabel, ftable in filters:
            for ilabel, itable in iods:
                ov = copy.deepcopy(data.get("overrides", {}))
                if ftable:
                    ov["filter"] = ftable
                if itable:
                    ov["iod"] = itable
                if extra:
                    ov = merge_settings(ov, extra)
                    for table, value in extra.items():  # keys of the scenario's own table
                        if isinstance(value, dict) and isinstance(base.raw.get(table), dict) \
                                and table not in ((("filter",) if ftable else ()) + (("iod",) if itable else ())):
                            ov[table] = merge_settings(base.raw[table], ov[table])
                try:
                    variant = base.with_overrides(ov, reg)   # validates this combination now
                except ConfigError as exc:
                    if extra:
                        raise ConfigError(f"{exc} (with {' '.join('--set ' + i for i in settings)})") from None
                    raise
                fl = flabel or variant.components["filter"].name
                il = ilabel or variant.components["iod"].name
                for seed in seeds:
                    rid = run_id(base.name, fl, il, seed)
                    specs.append(RunSpec(rid, scen_path, int(seed), ov, str(out / "runs" / rid),
                                         base.name, fl, il, fingerprint=scenario_fingerprint(variant, seed)))
    ids = [s.run_id for s in specs]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{p}: two runs share an id; give repeated filters or IOD tables distinct 'label's")
    return data, specs, out


def _settings_suffix(settings: list[str] | None) -> str:
    if not settings:
        return ""
    import hashlib

    return "__set-" + hashlib.sha256("\n".join(settings).encode()).hexdigest()[:8]


def make_executor(workers: int | None = None, dask: str | None = None):
    """A concurrent.futures Executor: local processes, or a Dask cluster ('local' or an address)."""
    if workers is not None:
        check_count(workers, "--workers", 1, 1024)
    n = workers or os.cpu_count() or 1
    if dask:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ConfigError("--dask needs the optional dependency: pip install 'cistrack[dask]'") from None
        if dask == "local":
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                   host="127.0.0.1")
            client = Client(cluster)
        else:
            try:
                client = Client(dask, timeout=10)
            except (OSError, TimeoutError, ValueError) as exc:
                raise ConfigError(f"--dask {dask!r}: cannot connect to a Dask scheduler there within 10 s "
                                  f"({type(exc).__name__}: {exc}); give a reachable address "
                                  "(e.g. tcp://127.0.0.1:8786) or 'local'") from None
        ex = client.get_executor()
        ex._cistrack_client = client  # closed by run_study
        return ex
    import multiprocessing as mp
    cores = os.cpu_count() or 1
    return cf.ProcessPoolExecutor(max_workers=n, mp_context=mp.get_context("spawn"),  # workers end with this process
                                  initializer=init_worker, initargs=(max(1, cores // n), os.getpid()))


def close_dask_client(ex) -> None:
    """Close the Dask client (and its local cluster) that :func:`make_executor` attached to
    ``ex``; nothing for a process pool."""
    client = getattr(ex, "_cistrack_client", None)
    if client is not None:
        cluster = client.cluster
        client.close()
        if cluster is not None:
            cluster.close()


def run_study(path_or_name: str | Path, out_dir: str | Path | None = None, workers: int | None = None,
              dask: str | None = None, executor: cf.Executor | None = None, progress: bool = True,
              rerun_dir: str | Path | None = None, settings: list[str] | None = None,
              first_seed: int | None = None, n_seeds: int | None = None) -> dict:
    """Run every missing run of a study. Returns counts, the study directory, the runs that are
    not done on disk afterwards (``problems``: (run id, why) pairs; ``failed`` counts them) and the
    plan it ran (``specs``: every :class:`RunSpec` of the study, done before or now, in plan order).

    The study directory must be new, empty or this study's own
    (:func:`cistrack.results.output_paths.check_study_dir`), and only one study process at a time
    may write there (:func:`cistrack.studies.study_lock.study_lock`).
    ``rerun_dir``: write one rerun recording per run there, named ``<run id>.rrd``.
    ``settings``: ``--set`` items applied to every run (see :func:`plan_runs`).
    ``first_seed``, ``n_seeds``: other seeds than the study file's (see :func:`plan_runs`).
    """
    import dataclasses

    from cistrack.results.output_paths import STUDY_RECORD, check_study_dir
    from cistrack.studies.execution import run_all, run_problems, shutdown
    from cistrack.studies.study_lock import study_lock

    refuse_in_a_starting_worker()
    if workers is not None:
        check_count(workers, "--workers", 1, 1024)
    if settings is None:  # a study folder run again keeps (and records) the settings it was run with
        settings = recorded_settings(path_or_name)
    data, specs, out = plan_runs(path_or_name, out_dir, settings, first_seed, n_seeds)
    source = study_source(path_or_name)
    name = str(data.get("name") or Path(source).stem)
    where = "--out" if out_dir is not None else "the study directory"
    check_study_dir(out, name, source, where)
    if rerun_dir is not None:
        from cistrack.results.output_paths import check_writable_dir

        check_writable_dir(rerun_dir, "--rerun")
        specs = [dataclasses.replace(s, rerun_path=str(Path(rerun_dir) / f"{s.run_id}.rrd")) for s in specs]
    with study_lock(out, where):
        record = {"source": source, **data, "name": name, "settings": list(settings or []),
                  "run_seeds": sorted({sp.seed for sp in specs})}
        try:
            write_text_atomic(out / STUDY_RECORD, json.dumps(record, indent=2, default=str))
        except OSError as exc:
            raise CistrackError(f"{where} {out}: cannot write {STUDY_RECORD} ({exc.strerror or exc}); "
                                f"nothing was run") from None
        states = {s.run_id: run_state(s.out_dir, s.fingerprint) for s in specs}
        todo = [s for s in specs if states[s.run_id] != "done"]
        _say_rerun(specs, states)
        own = executor is None
        ex = executor or (make_executor(workers, dask) if todo else None)
        bar = None
        if progress and todo:
            from tqdm.auto import tqdm
            bar = tqdm(total=len(todo), desc=f"study {name}", unit="run")
        said: dict[str, str] = {}
        ended = False
        try:
            if todo:
                said = run_all(ex, todo, run_spec, bar)
            ended = True
        finally:
            if bar is not None:
                bar.close()
            if own and ex is not None:
                shutdown(ex, cancel=not ended)
                close_dask_client(ex)
        problems = run_problems(specs, said)  # from disk, not from what the workers said
    bad = {rid for rid, _ in problems}
    return {"name": name, "out_dir": out, "completed": sum(1 for s in todo if s.run_id not in bad),
            "skipped": len(specs) - len(todo), "failed": len(problems), "total": len(specs),
            "problems": problems, "specs": specs}


def _say_rerun(specs: list[RunSpec], states: dict[str, str]) -> None:
    """Tell on stderr which finished runs are stale and which were left by a process that is gone."""
    stale = [s.run_id for s in specs if states[s.run_id] == "stale"]
    if stale:
        print(f"study: {len(stale)} finished run(s) were made with another scenario, seed or input file "
              f"(fingerprint changed) and are run again: {', '.join(stale[:5])}"
              + (" ..." if len(stale) > 5 else ""), file=sys.stderr)
    gone = [s.run_id for s in specs if states[s.run_id] == "gone"]
    if gone:
        print(f"study: {len(gone)} run(s) were left 'running' by a process that is gone (interrupted, e.g. "
              f"killed) and are run again: {', '.join(gone[:5])}" + (" ..." if len(gone) > 5 else ""), file=sys.stderr)
