"""Comparative studies: scenarios x filters x IOD variants x seeds through any Executor.

A study file (TOML)::

    name = "filter-comparison"
    description = "PGM vs UKF vs EnKF on paper Example 1, three IOD range models"
    scenarios = ["example-1"]                  # built-in names or paths relative to this file
    filters = ["pgm", "ukf", "enkf"]           # names, or tables {name = ..., label = ..., params}
    iod = ["noisy-range", "uniform-range"]     # the same; omit to keep each scenario's own
    seeds = [1, 2, 3]                          # or n_seeds = 10 (seeds 1..10), with first_seed = 500
                                               # seeds 500..509
    sweep = {"truth.maneuvers.delta_v_ms" = [0.1, 1.0], "maneuvers.response" = ["none", "inflate"]}
    [overrides]                                # applied to every scenario first
    duration_days = 6.6                        # a filter or iod table here applies under each
                                               # filters/iod entry too (the entry's own keys win)

A ``sweep`` crosses every scenario entry with every combination of its values, each applied as a
``--set`` item after the study's overrides (and before the command line's ``--set``); every
combination is validated before any run. A swept run's scenario label, hence its id and its report
group, names the combination: ``example-1-burn[dv=0.3,resp=inflate]`` (:func:`sweep_label`). A
scenario entry given as a table ``{name = "example-1", sweep = false}`` is not swept (``sweep =
["maneuvers.response"]``: only those settings); a setting that does not apply to a scenario it is
swept over is refused, naming the study file, the key and the scenario, and an invalid value of one
that does apply naming the setting, the value and why. A study without a sweep names its runs as
before.

Each run is written to ``<out>/runs/<run id>/`` as it finishes (see :mod:`cistrack.results.store`);
running the study again runs only what is missing (reports: :mod:`cistrack.studies.report`). Runs are pure functions of (scenario, seed):
the same seed gives the same numbers under any executor.
"""
from __future__ import annotations

import concurrent.futures as cf
import copy
import dataclasses
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cistrack import units
from cistrack.errors import CistrackError, ConfigError
from cistrack.studies.lost_runs import refuse_in_a_starting_worker
from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.fingerprint import scenario_fingerprint
from cistrack.studies.study_file import (_study_seeds, builtin_studies, load_study, recorded_settings, scenario_base,
                                         scenario_entry, study_source, study_sweep)
from cistrack.studies.resume import run_state
from cistrack.scenario.limits import check_count, check_path_component
from cistrack.scenario.settings import describe_settings
from cistrack.scenario.settings import settings_suffix as _settings_suffix  # the name it had here
from cistrack.studies.workers import execute_run, init_worker, run_spec
from cistrack.runs.run_id import run_id


__all__ = ["RunSpec", "StudyOptions", "load_study", "plan_runs", "execute_run", "run_study", "close_dask_client",
           "builtin_studies", "make_executor", "sweep_label", "sweep_item", "base_scenario_name", "done_line"]


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
    sweep: tuple = ()      # the sweep combination: ((dotted setting, value), ...); () without a sweep


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
    from cistrack.scenario.settings import parse_settings

    data, p = load_study(path_or_name)  # p: the study file, or a study directory's study.json
    recorded = recorded_settings(path_or_name)  # a study results directory: its own runs, in place
    from_record = ""
    if recorded is not None:
        from_record = f"{p}: key 'settings'" if settings is None or list(settings) == recorded else ""
        settings = recorded if settings is None else settings
        out_dir = path_or_name if out_dir is None else out_dir
    name = check_path_component(data.get("name", p.stem), f"{p}: key 'name'")
    try:
        extra = parse_settings(settings)
    except ConfigError as exc:
        if not from_record:
            raise
        raise ConfigError(f"{from_record}: {exc}") from None
    out = Path(out_dir) if out_dir else Path("studies_out") / (name + _settings_suffix(settings))
    seeds = _study_seeds(data, p, first_seed, n_seeds)
    sweep = tuple((k, tuple(v)) for k, v in study_sweep(data, p))
    _check_settings_against_sweep(settings, sweep, p)
    _check_settings_against_study(settings, data, p)
    grid = _Grid(filters=[_label_and_table(f, "filters", p) for f in (data.get("filters") or [None])],
                 iods=[_label_and_table(f, "iod", p) for f in (data.get("iod") or [None])],
                 overrides=data.get("overrides", {}), extra=extra, settings=settings, seeds=seeds, out=out,
                 sweep=sweep, study=p, base=scenario_base(path_or_name, p), settings_from=from_record)
    for key, entries in (("filters", grid.filters), ("iod", grid.iods)):
        _check_distinct_labels(entries, key, p)
    reg = default_registry()
    specs: list[RunSpec] = []
    for sc in data["scenarios"]:
        specs += _scenario_runs(sc, p, grid, reg)
    _check_distinct_ids(specs, p)
    return data, specs, out


def _check_distinct_labels(entries: list[tuple[str, dict | None]], key: str, p: Path) -> None:
    """Refuse two entries of the study's ``filters`` or ``iod`` list that label their runs alike
    (two tables of one component without a ``label``, or the same ``label``): their runs would share
    ids, hence results directories."""
    seen: dict[str, int] = {}
    for i, (label, table) in enumerate(entries):
        j = seen.setdefault(label, i)
        if j == i or table is None:
            continue
        raise ConfigError(f"{p}: entries {j + 1} and {i + 1} of {key!r} both label their runs {label!r}, so their runs "
                          f"would share ids and results directories; give each a distinct 'label' (e.g. "
                          f"{{ name = {json.dumps(str(table.get('name')))}, label = {json.dumps(label + '-2')}, ... }}), or "
                          "list it once")


def _check_distinct_ids(specs: list[RunSpec], p: Path) -> None:
    """Refuse two runs of one id (one results directory), naming the id and what the two share."""
    first: dict[str, RunSpec] = {}
    for s in specs:
        other = first.setdefault(s.run_id, s)
        if other is s:
            continue
        if other.sweep != s.sweep:
            why = (f"the sweep values {_sweep_text(other.sweep)} and {_sweep_text(s.sweep)} label their runs "
                   "alike; give the sweep distinct values")
        elif other.filter_label != s.filter_label or other.iod_label != s.iod_label or other.scenario != s.scenario:
            why = "give repeated filters or IOD tables distinct 'label's"
        else:
            why = (f"scenario {s.scenario_name!r} is listed twice with the same filter, IOD and seed; list it once")
        raise ConfigError(f"{p}: two runs share the id {s.run_id!r}: {why}")


def _sweep_text(combination: tuple) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in combination) or "(none)"


@dataclass(frozen=True)
class _Grid:
    """What each scenario of a study is crossed with: the (label, table or None) filter and IOD
    variants, the study's overrides, the parsed ``--set`` items (``extra``) and their text
    (``settings``), the seeds, and the study directory the runs go into."""

    filters: list[tuple[str, dict | None]]
    iods: list[tuple[str, dict | None]]
    overrides: dict
    extra: dict
    settings: list[str] | None
    seeds: list[int]
    out: Path
    sweep: tuple = ()
    """The study's sweep: ((dotted setting, (values...)), ...)."""
    study: Path = Path()
    """The study file, or a study directory's study.json (named in errors)."""
    base: Path = Path()
    """The file beside which relative scenario paths are read (:func:`scenario_base`)."""
    settings_from: str = ""
    """Where ``settings`` come from when a study directory's record gives them (named in errors
    instead of ``--set``), else ""."""


def _scenario_source(sc: str, p: Path) -> str | Path:
    """A study's scenario entry as load_scenario takes it: a path relative to the study file
    ``p`` when one exists there, else the entry's own path when it exists, else a built-in name."""
    from cistrack.scenario.loading import relative_base

    sp = Path(sc)
    if not sp.is_absolute() and (relative_base(p) / sp).exists():
        sp = relative_base(p) / sp
    return sp if sp.exists() else sc


def _where_looked(sc: str, base: Path) -> str:
    """For a scenario entry ``sc`` written as a file (a .toml suffix or a folder in it) that exists
    nowhere: where it was looked for, beside the study file ``base`` and from the working folder
    ("" for an entry written as a built-in scenario's name, whose own error lists the names)."""
    from cistrack.scenario.loading import relative_base

    if Path(sc).suffix != ".toml" and "/" not in sc:
        return ""
    if Path(sc).is_absolute():
        return f"scenario file not found: {sc}"
    return (f"scenario file not found: neither {relative_base(base) / sc} (beside the study file) nor "
            f"{Path.cwd() / sc} (from the working folder) exists")


_SHORT_NAMES = {"delta_v_ms": "dv", "response": "resp", "t_days": "t", "detector": "det", "n_particles": "np",
                "duration_days": "days", "n_components": "nc", "direction": "dir"}
"""Short names of common sweep settings (by their last part) in run labels; others keep their last part."""


def _sweep_value_text(v: Any) -> str:
    """A sweep value as a label shows it: 0.3, 1 (for 1.0), inflate, true."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        text = repr(v)
        return text[:-2] if text.endswith(".0") else text
    return str(v)


def sweep_names(keys: list[str]) -> dict[str, str]:
    """Dotted sweep setting -> its name in labels: a short name (:data:`_SHORT_NAMES`) or its last
    part, the whole dotted setting where two settings would share a name."""
    short = {k: _SHORT_NAMES.get(k.rsplit(".", 1)[-1], k.rsplit(".", 1)[-1]) for k in keys}
    seen = [n for n in short.values()]
    return {k: (n if seen.count(n) == 1 else k) for k, n in short.items()}


def sweep_label(scenario: str, combo: tuple, names: dict[str, str] | None = None) -> str:
    """``sweep_label("example-1-burn", (("truth.maneuvers.delta_v_ms", 0.3), ("maneuvers.response",
    "inflate"))) == "example-1-burn[dv=0.3,resp=inflate]"``; the scenario's own name without a
    combination. Stable (the settings in the study file's order) and one path component."""
    if not combo:
        return scenario
    names = names or sweep_names([k for k, _ in combo])
    return f"{scenario}[{','.join(f'{names[k]}={_sweep_value_text(v)}' for k, v in combo)}]"


def base_scenario_name(label: str, combo: tuple = ()) -> str:
    """The scenario's own name of a (possibly swept) scenario label."""
    return label[:label.index("[")] if combo and "[" in label else label


def sweep_item(key: str, value: Any) -> str:
    """A sweep setting and value as the ``--set`` item it amounts to (``maneuvers.response="none"``)."""
    return f"{key}={json.dumps(value)}"


def _check_settings_against_sweep(settings: list[str] | None, sweep: tuple, p: Path) -> None:
    """Refuse a ``--set`` item that sets a swept setting (or a table holding one): it would give
    every combination the same value under different labels."""
    for item in settings or []:
        key = ".".join(part.strip() for part in item.partition("=")[0].split("."))
        hit = [k for k, _ in sweep if k == key or k.startswith(key + ".")]
        if hit:
            raise ConfigError(f"{describe_settings([item])}: {p}: key 'sweep' already varies {hit[0]!r}; change the study's "
                              "sweep (or use a study file without it) instead of setting it for every run")


def _check_settings_against_study(settings: list[str] | None, data: dict, p: Path) -> None:
    """Refuse a ``--set`` item that sets what the study itself chooses for each run: the seed, and
    the filter's or IOD's name (or whole table) when the study lists them. ``--set filter.name=ukf``
    had run the UKF in every entry, filed and reported under the entries' names ("pgm", "enkf",
    identical numbers), and ``--set seed=5`` had been ignored (probe M6)."""
    for item in settings or []:
        key = ".".join(part.strip() for part in item.partition("=")[0].split("."))
        if key == "seed":
            raise ConfigError(f"{describe_settings([item])}: a study's runs take their seeds from {p}'s key 'seeds' "
                              "(or 'n_seeds' and 'first_seed'); give --first-seed and --n-seeds instead")
        for table, listed in (("filter", "filters"), ("iod", "iod")):
            if listed in data and key in (table, f"{table}.name"):
                raise ConfigError(f"{describe_settings([item])}: {p}: key {listed!r} chooses the {table} of each run; "
                                  f"change it there (or set the {table}'s parameters with --set {table}.KEY=VALUE)")


def _combinations(sweep: tuple, keys: list[str]) -> list[tuple]:
    """Every combination ((setting, value), ...) of the sweep settings ``keys`` ([()] for none)."""
    import itertools

    chosen = [(k, values) for k, values in sweep if k in keys]
    return [tuple(zip([k for k, _ in chosen], vals)) for vals in itertools.product(*[v for _, v in chosen])]


def _scenario_runs(entry: Any, p: Path, grid: _Grid, reg) -> list[RunSpec]:
    """The runs of scenario entry ``entry``: sweep combinations x filters x IOD variants x seeds,
    each variant validated."""
    from cistrack.scenario.loading import load_scenario

    sc, keys = scenario_entry(entry, p, [k for k, _ in grid.sweep])
    source = _scenario_source(sc, grid.base)
    try:
        base = load_scenario(source, reg)
    except ConfigError as exc:
        if not isinstance(source, str):  # a scenario file: its own error names it
            raise
        raise ConfigError(f"{p}: key 'scenarios', entry {sc!r}: {_where_looked(sc, grid.base) or exc}") from None
    names = sweep_names([k for k, _ in grid.sweep])
    specs: list[RunSpec] = []
    for combo in _combinations(grid.sweep, keys):
        label = check_path_component(sweep_label(base.name, combo, names), f"{p}: key 'sweep': the run label")
        for flabel, ftable in grid.filters:
            for ilabel, itable in grid.iods:
                specs += _variant_runs(base, label, combo, (flabel, ftable, ilabel, itable), grid, reg, entry=str(sc))
    return specs


def _variant_runs(base, label: str, combo: tuple, variant_tables: tuple, grid: _Grid, reg,
                  entry: str = "") -> list[RunSpec]:
    """The runs (one per seed) of scenario ``base`` under the sweep combination ``combo`` (its label
    ``label``) with one filter and IOD variant ``(filter label, table, IOD label, table)``; ``entry``:
    the study's ``scenarios`` entry, as written, that named ``base``."""
    flabel, ftable, ilabel, itable = variant_tables
    ov = _variant_overrides(grid, base, ftable, itable, combo)
    variant = _validated_variant(base, ov, grid, reg, combo, {"filter": ftable, "iod": itable}, entry)
    _refuse_unflown(variant, grid.study, reg)
    fl = flabel or variant.components["filter"].name
    il = ilabel or variant.components["iod"].name
    scen_path = str(Path(base.source).resolve())
    specs = []
    for seed in grid.seeds:
        rid = run_id(label, fl, il, seed)
        specs.append(RunSpec(rid, scen_path, int(seed), ov, str(grid.out / "runs" / rid), label, fl, il,
                             fingerprint=scenario_fingerprint(variant, seed), sweep=combo))
    return specs


def _refuse_unflown(scenario, study: Any, reg) -> None:
    """ConfigError naming the study, the scenario file and the burn when the scenario's
    ``[truth.maneuvers]`` plan gives a burn outside its run (not flown): the study's maneuver
    results would be reported as if it were (probe N4: '1 runs completed', nothing said)."""
    if not scenario.truth_maneuvers:
        return
    days = float(units.tu_to_days(scenario.duration))
    outside = scenario.truth_maneuvers.build(reg).burns_outside(0.0, float(scenario.duration))
    if outside:
        raise ConfigError(f"{study}: scenario {scenario.source}: [truth.maneuvers]: {'; '.join(outside)} lies outside "
                          f"the run (0 to {days:g} days) and would not be flown; a study does not run a maneuver "
                          "scenario without its burns: move the burn inside the run or lengthen duration_days")


def _sweep_settings(combo: tuple) -> dict:
    """A sweep combination as parsed ``--set`` items (nested tables)."""
    from cistrack.scenario.settings import merge_settings

    out: dict = {}
    for key, value in combo:
        node: Any = value
        for part in reversed(key.split(".")):
            node = {part.strip(): node}
        out = merge_settings(out, node)
    return out


def _variant_overrides(grid: _Grid, base, ftable: dict | None, itable: dict | None, combo: tuple = ()) -> dict:
    """The study's overrides with the variant's filter and IOD tables (each over the overrides' own
    table of that name: an entry's keys win, the other overrides stay), then the sweep combination,
    then the ``--set`` items; a table they set that the variant does not replace is merged into the
    scenario's own table."""
    from cistrack.scenario.settings import merge_settings

    ov = copy.deepcopy(grid.overrides)
    for table, entry in (("filter", ftable), ("iod", itable)):
        if entry:  # the entry's component, with the study's overrides of that table under the entry's own keys
            ov[table] = merge_settings(ov[table], entry) if isinstance(ov.get(table), dict) else entry
    replaced = (("filter",) if ftable else ()) + (("iod",) if itable else ())
    for extra in (_sweep_settings(combo), grid.extra):
        if not extra:
            continue
        ov = merge_settings(ov, extra)
        for table, value in extra.items():  # keys of the scenario's own table
            if isinstance(value, dict) and isinstance(base.raw.get(table), dict) and table not in replaced:
                ov[table] = merge_settings(base.raw[table], ov[table])
    return ov


def _validated_variant(base, ov: dict, grid: _Grid, reg, combo: tuple = (), entries: dict | None = None,
                       entry: str = ""):
    """The scenario ``base`` with the overrides ``ov``, validated now; a ConfigError names the
    study file's key behind a bad setting (``overrides``, or the ``filters``/``iod`` entry among
    ``entries``), the sweep combination and the ``--set`` items when there are any; advice quotes
    the ``scenarios`` entry as written (``entry``, default the scenario's name)."""
    try:
        return base.with_overrides(ov, reg)
    except ConfigError as exc:
        from cistrack.studies.study_file import overrides_error, sweep_error, variant_error

        swept = sweep_error(str(exc), grid.study, combo, base.name, base.source, entry or base.name)
        msg = (swept or overrides_error(str(exc), grid.study, grid.overrides, base.name, base.source, base.raw)
               or variant_error(str(exc), grid.study, entries or {}, base.name, base.source) or str(exc))
        if combo and not swept:
            msg += (f" ({grid.study}: key 'sweep': {' '.join(sweep_item(k, v) for k, v in combo)} on scenario "
                    f"{base.name!r})")
        if grid.extra:
            msg += (f" (with {grid.settings_from} = {grid.settings!r})" if grid.settings_from
                    else f" (with {describe_settings(grid.settings)})")
        if msg == str(exc):
            raise
        raise ConfigError(msg) from None


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
            from cistrack.studies.execution import check_dask_scheduler

            check_dask_scheduler(dask)  # a service that is not a scheduler: refused, never a hang
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


@dataclass(frozen=True)
class StudyOptions:
    """How :func:`run_study` runs a study; each field is also one of its keywords, and they may be
    given positionally after ``out_dir`` in this order.

    Attributes
    ----------
    workers : int or None               worker processes (the CPU count when None)
    dask : str or None                  a Dask cluster instead: 'local' or a scheduler address
    executor : Executor or None         run on this executor (neither made nor shut down here)
    progress : bool                     a progress bar on stderr
    rerun_dir : str, Path or None       write one rerun recording per run there, ``<run id>.rrd``
    settings : list of str or None      ``--set`` items applied to every run (see :func:`plan_runs`)
    first_seed, n_seeds : int or None   other seeds than the study file's (see :func:`plan_runs`)
    overwrite : bool                    run again finished runs the study file now plans otherwise
                                        (their results replaced); refused without it
    """

    workers: int | None = None
    dask: str | None = None
    executor: cf.Executor | None = None
    progress: bool = True
    rerun_dir: str | Path | None = None
    settings: list[str] | None = None
    first_seed: int | None = None
    n_seeds: int | None = None
    overwrite: bool = False


def run_study(path_or_name: str | Path, out_dir: str | Path | None = None, *args: Any,
              options: StudyOptions | None = None, **keywords: Any) -> dict:
    """Run every missing run of a study. Returns counts, the study directory, the runs that are
    not done on disk afterwards (``problems``: (run id, why) pairs; ``failed`` counts them) and the
    plan it ran (``specs``: every :class:`RunSpec` of the study, done before or now, in plan order).

    ``options`` (a :class:`StudyOptions`), each field of which may also be given as a keyword
    (a keyword wins) or positionally after ``out_dir``: ``workers``, ``dask``, ``executor``,
    ``progress``, ``rerun_dir``, ``settings``, ``first_seed``, ``n_seeds``, ``overwrite``.

    The study directory must be new, empty or this study's own
    (:func:`cistrack.results.output_paths.check_study_dir`), and only one study process at a time
    may write there (:func:`cistrack.studies.study_lock.study_lock`).
    """
    from cistrack.results.output_paths import check_study_dir
    from cistrack.studies.execution import run_problems
    from cistrack.studies.study_lock import study_lock

    opts = _study_options(args, options, keywords)
    refuse_in_a_starting_worker()
    if opts.workers is not None:
        check_count(opts.workers, "--workers", 1, 1024)
    settings = opts.settings
    if settings is None:  # a study folder run again keeps (and records) the settings it was run with
        settings = recorded_settings(path_or_name)
    data, specs, out = plan_runs(path_or_name, out_dir, settings, opts.first_seed, opts.n_seeds)
    source = study_source(path_or_name)
    name = str(data.get("name") or Path(source).stem)
    where = "--out" if out_dir is not None else "the study directory"
    check_study_dir(out, name, source, where)
    specs = _with_rerun_paths(specs, opts.rerun_dir)
    with study_lock(out, where):
        states = {s.run_id: run_state(s.out_dir, s.fingerprint) for s in specs}
        if not opts.overwrite:
            _refuse_replacing(specs, states, out, where)
        _write_study_record(out, where, {"source": source, **data, "name": name, "settings": list(settings or []),
                                         "run_seeds": sorted({sp.seed for sp in specs})})
        todo = [s for s in specs if states[s.run_id] != "done"]
        _say_rerun(specs, states)
        _remove_report_of_replaced_runs(out, specs, states)
        said = _run_todo(todo, opts, name)
        problems = run_problems(specs, said)  # from disk, not from what the workers said
        if todo:
            _remove_report_written_meanwhile(out)
    bad = {rid for rid, _ in problems}
    done = [s for s in todo if s.run_id not in bad]
    return {"name": name, "out_dir": out, "completed": len(done), "filter_failed": _filter_failed(done),
            "skipped": len(specs) - len(todo), "failed": len(problems), "total": len(specs),
            "problems": problems, "specs": specs}


def _filter_failed(done: list) -> int:
    """How many of the runs ``done`` (specs of runs done on disk) ended "filter-failed"."""
    from cistrack.results.run_status import run_status

    n = 0
    for s in done:
        try:
            n += run_status(s.out_dir)[0] == "filter-failed"
        except (OSError, ValueError):  # read a moment ago by run_problems: a run gone since is not counted
            continue
    return n


def done_line(res: dict[str, Any]) -> str:
    """The line a finished ``study run`` prints for :func:`run_study`'s answer ``res``: runs
    completed (and how many of them ended with their filter raising), already done, failed."""
    ff = res.get("filter_failed") or 0
    raised = f" ({ff} of them filter-failed: the filter raised; the report lists them)" if ff else ""
    return (f"study '{res['name']}': {res['completed']} runs completed{raised}, {res['skipped']} already done, "
            f"{res['failed']} failed -> {res['out_dir']}")


def _study_options(args: tuple, options: StudyOptions | None, keywords: dict[str, Any]) -> StudyOptions:
    """``options`` with the fields given positionally (``args``, in field order) or as keywords
    replaced; a TypeError like Python's for too many, repeated or unknown arguments."""
    names = [f.name for f in dataclasses.fields(StudyOptions)]
    if len(args) > len(names):
        raise TypeError(f"run_study() takes from 1 to {2 + len(names)} positional arguments "
                        f"but {2 + len(args)} were given")
    given = dict(zip(names, args))
    twice = [k for k in keywords if k in given]
    if twice:
        raise TypeError(f"run_study() got multiple values for argument {twice[0]!r}")
    unknown = [k for k in keywords if k not in names]
    if unknown:
        raise TypeError(f"run_study() got an unexpected keyword argument {unknown[0]!r}")
    return dataclasses.replace(options or StudyOptions(), **given, **keywords)


def _with_rerun_paths(specs: list[RunSpec], rerun_dir: str | Path | None) -> list[RunSpec]:
    """The runs, each recording to ``<rerun_dir>/<run id>.rrd`` when ``rerun_dir`` is given (checked
    writable)."""
    if rerun_dir is None:
        return specs
    from cistrack.results.output_paths import check_writable_dir

    check_writable_dir(rerun_dir, "--rerun")
    return [dataclasses.replace(s, rerun_path=str(Path(rerun_dir) / f"{s.run_id}.rrd")) for s in specs]


def _write_study_record(out: Path, where: str, record: dict) -> None:
    """Write the study record (:data:`cistrack.results.output_paths.STUDY_RECORD`) into ``out``."""
    from cistrack.results.output_paths import STUDY_RECORD

    try:
        write_text_atomic(out / STUDY_RECORD, json.dumps(record, indent=2, default=str))
    except OSError as exc:
        raise CistrackError(f"{where} {out}: cannot write {STUDY_RECORD} ({exc.strerror or exc}); "
                            f"nothing was run") from None


def _run_todo(todo: list[RunSpec], opts: StudyOptions, name: str) -> dict[str, str]:
    """Run ``todo`` on the given executor, or on one made here and shut down afterwards (its
    pending runs cancelled when interrupted); returns what the workers said per run id."""
    from cistrack.studies.execution import run_all, shutdown

    own = opts.executor is None
    ex = opts.executor or (make_executor(opts.workers, opts.dask) if todo else None)
    bar = None
    if opts.progress and todo:
        from cistrack.runs.progress import bar_class, bar_columns
        bar = bar_class()(total=len(todo), desc=f"study {name}", unit="run", ncols=bar_columns(),
                   disable=sys.stderr is None)  # 2>&-: no bar
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
    return said


def _refuse_replacing(specs: list[RunSpec], states: dict[str, str], out: Path, where: str) -> None:
    """ConfigError when finished runs in ``out`` were made with another scenario, seed or input
    file than the study now plans for them (running them again would replace their results)."""
    stale = [s.run_id for s in specs if states[s.run_id] == "stale"]
    if stale:
        raise ConfigError(f"{where} {out}: {len(stale)} finished run(s) there were made with another scenario, "
                          f"settings, seed or input file than the study now gives them ({', '.join(stale[:3])}"
                          + (" ..." if len(stale) > 3 else "") + "); add --overwrite (overwrite=True) to run them "
                          "again, replacing their results, or give another --out")


def _say_rerun(specs: list[RunSpec], states: dict[str, str]) -> None:
    """Tell on stderr which finished runs are stale, which have a damaged manifest and which were
    left by a process that is gone (each notice wrapped within 120 columns)."""
    stale = [s.run_id for s in specs if states[s.run_id] == "stale"]
    if stale:
        _notice(f"{len(stale)} finished run(s) were made with another scenario, seed or input file "
                f"(fingerprint changed) and are run again: {', '.join(stale[:5])}" + (" ..." if len(stale) > 5 else ""))
    damaged = [str(Path(s.out_dir) / "manifest.json") for s in specs if states[s.run_id] == "damaged"]
    if damaged:
        _notice(f"{len(damaged)} run(s) whose manifest.json is cut short or damaged (it cannot be read "
                f"back) are run again: {', '.join(damaged[:3])}" + (" ..." if len(damaged) > 3 else ""))
    gone = [s.run_id for s in specs if states[s.run_id] == "gone"]
    if gone:
        _notice(f"{len(gone)} run(s) were left 'running' by a process that is gone (interrupted, e.g. "
                f"killed) and are run again: {', '.join(gone[:5])}" + (" ..." if len(gone) > 5 else ""))


REPORT_FOLDER = "report"
"""The folder of a study directory that ``cistrack study report`` writes (:mod:`cistrack.studies.report`)."""


def _remove_report_of_replaced_runs(out: Path, specs: list[RunSpec], states: dict[str, str]) -> None:
    """Remove ``out/report`` before any run is made: before finished runs made otherwise are run
    again (``--overwrite``) it describes the runs they replace, as a run's exports describe it (a
    run removes those); before runs are added or resumed it counts fewer runs than there will be."""
    import shutil

    report = out / REPORT_FOLDER
    if all(states[s.run_id] == "done" for s in specs) or not report.is_dir():
        return
    if report.is_symlink():
        report.unlink()  # the link only, as a report replaces it
    else:
        shutil.rmtree(report)
    why = ("described the runs replaced now" if any(states[s.run_id] == "stale" for s in specs)
           else "counted the runs done before this study run")
    _notice(f"the report in {report} {why} and is removed; 'cistrack study report' writes it again")


def _remove_report_written_meanwhile(out: Path) -> None:
    """Remove ``out/report`` at the end of a study run that ran runs: it removed any report when it
    began, so one there now was written by 'cistrack study report' while runs were still to come, and
    counts fewer than the study holds now (probe I3: it had been left in place, reading like the final one)."""
    import shutil

    report = out / REPORT_FOLDER
    if not (report.is_dir() or report.is_symlink()):
        return
    if report.is_symlink():
        report.unlink()
    else:
        shutil.rmtree(report, ignore_errors=True)
    _notice(f"the report in {report} was written while this study ran, before its runs were all done, and is "
            "removed; 'cistrack study report' writes it again")


def _notice(text: str, width: int = 120) -> None:
    """``study: text`` on stderr, wrapped within ``width`` columns under the text."""
    import textwrap

    from cistrack.runs.progress import eprint

    eprint("\n".join(textwrap.wrap(text, width=width, initial_indent="study: ", subsequent_indent="       ",
                                   break_on_hyphens=False, break_long_words=False)))
