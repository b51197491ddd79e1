"""cistrack's public Python API: what notebook users and plugin authors import.

Running::

    import cistrack as ct

    r = ct.run("quick", seed=2)                       # a built-in scenario, or a path to a TOML file
    r.verdict.kind, r.summary.final["pos_err_km"]      # "tracking", 3.1
    r.steps                                            # one row per step (pandas DataFrame)
    r2 = ct.run("example-1", seed=5, settings={"filter.n_particles": 2000}, out="runs/ex1-5")
    again = ct.read_run("runs/ex1-5")                  # the same run, read back from its folder
    fig = r.plot()                                     # error, sigma, NEES with its band, entropy
    s = ct.study("quick-comparison", n_seeds=2)        # a StudyResult: s.table, s.runs, s.plot()
    [one] = ct.fit("observations.psv")                 # an ObjectFit per object: one.ok, one.result

Writing a plugin (see docs/plugins.md)::

    from cistrack.api import Clusterer, Component, check_int, hookimpl, ParticleCloud

Importing this module is cheap enough for a plugin module to do it: the names only running needs
(:class:`Scenario`, :class:`RunSummary`, :class:`Verdict`, :class:`ObjectFit`) load on first
access, and the functions import the pipeline when called.

Every name here is a promise: it stays importable from ``cistrack.api`` (and the run functions
from ``cistrack``) across releases; a name that moves keeps working from its old path with a
DeprecationWarning for at least one release (:mod:`cistrack._moved`).
"""
from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cistrack.errors import (CistrackError, ConfigError, DuplicateComponentError, FilterError, IODError,
                             MeasurementError, ParameterError, UnknownComponentError, quoted)
from cistrack.interfaces import (KINDS, Body, Clusterer, Dynamics, Exporter, Filter, IODMethod, Pass,
                                 Propagation, RangePrior, Reader, ReferenceOrbit, Schedule, Sensor)
from cistrack.interfaces.component import (Component, check_choice, check_int, check_nonnegative,
                                           check_positive, check_range)
from cistrack.interfaces.pgm_steps import (ClusteredParticles, ComponentUpdate, KernelUpdate, ParticlePrediction,
                                           PosteriorDraw, Reanchor)
from cistrack.interfaces.metric import StepMetric
from cistrack.interfaces.preset import preset
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.model.measurement import Measurement, MeasurementSet
from cistrack.plugin.hookspecs import hookimpl
from cistrack.plugin.registry import Registry, default_registry, load_registry
from cistrack.propagation import CompiledDynamics

if TYPE_CHECKING:
    import pandas
    import pyarrow
    from matplotlib.figure import Figure

    from cistrack.evaluation.custody import Verdict
    from cistrack.evaluation.run_summary import RunSummary
    from cistrack.fitting.from_observations import ObjectFit
    from cistrack.scenario.loading import Scenario

__all__ = [
    # running scenarios
    "run", "read_run", "load_scenario", "Run", "Scenario", "RunSummary", "Verdict", "study", "StudyResult", "fit",
    "ObjectFit", "read_fit",
    # the registry
    "Registry", "default_registry", "load_registry", "KINDS",
    # writing plugins: interfaces, parameters, hooks, beliefs, measurements, propagation
    "Component", "check_positive", "check_nonnegative", "check_range", "check_choice", "check_int",
    "Dynamics", "Body", "Propagation", "Sensor", "Schedule", "Pass", "IODMethod", "RangePrior", "Clusterer",
    "Filter", "Reader", "Exporter", "ReferenceOrbit", "hookimpl", "CompiledDynamics", "preset",
    # the PGM's swappable steps (kinds pgm-prediction, pgm-update, pgm-draw, pgm-kernel, pgm-reanchor)
    "ParticlePrediction", "ComponentUpdate", "PosteriorDraw", "KernelUpdate", "Reanchor", "ClusteredParticles",
    # a metric of every step (hook cistrack_metric_stages)
    "StepMetric",
    "Belief", "ParticleCloud", "GaussianMixture", "Measurement", "MeasurementSet",
    # errors
    "CistrackError", "ConfigError", "DuplicateComponentError", "FilterError", "IODError", "MeasurementError",
    "ParameterError", "UnknownComponentError",
]

#: Names that only running needs, loaded on first access (PEP 562): plugin modules import from
#: this module, and the results, evaluation, scenario and fit workflow packages behind these
#: names are not theirs to pay for (nor to import back while they load).
_LAZY = {"RunSummary": "cistrack.evaluation.run_summary", "Verdict": "cistrack.evaluation.custody",
         "Scenario": "cistrack.scenario.loading", "ObjectFit": "cistrack.fitting.from_observations"}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'cistrack.api' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


#: The scenario :func:`run` runs when given none: the paper's Example 1 with the PGM filter.
DEFAULT_SCENARIO = "example-1"


@dataclass(frozen=True)
class Run:
    """One run's outcome: its typed summary, its per-step rows and, if it wrote one, its folder.

    Attributes
    ----------
    summary : RunSummary
        Status, final verdict, counts, consistency and the final metrics (km, m/s, cm/s).
    directory : Path or None
        The results folder (``steps.parquet``, ``manifest.json``), or None for a run kept in memory.
    rows : tuple of dict
        One dict per step, the columns of ``steps.parquet`` (see ``docs/`` and
        :func:`cistrack.results.step_table.step_row`).
    """

    summary: RunSummary
    directory: Path | None = None
    rows: tuple[dict[str, Any], ...] = field(default=(), repr=False)

    @property
    def run_id(self) -> str:
        return self.summary.run_id

    @property
    def seed(self) -> int:
        return self.summary.seed

    @property
    def status(self) -> str:
        """``"finished"`` or ``"filter-failed"``."""
        return self.summary.status

    @property
    def verdict(self) -> Verdict:
        """The final verdict: ``.kind`` is tracking, not-converged, lost, diverged, filter-failed or no-truth."""
        return self.summary.verdict

    @property
    def final(self) -> dict[str, float]:
        """Metrics of the last update: per-axis sigmas (km, cm/s), errors (km, m/s), NEES, entropy;
        one that is undefined is NaN in the run's own process and None once read back (the
        manifest, strict JSON, writes it as null)."""
        return dict(self.summary.final)

    def table(self) -> pyarrow.Table:
        """The per-step table as a pyarrow Table (the contents of ``steps.parquet``)."""
        import pyarrow as pa

        if self.rows:  # every column any row has (the first, the IOD's, has no NIS)
            names = list(dict.fromkeys(k for row in self.rows for k in row))
            return pa.Table.from_pydict({k: [row.get(k) for row in self.rows] for k in names})
        if self.directory is not None:
            from cistrack.results.store import read_steps

            try:
                return read_steps(self.directory)
            except FileNotFoundError as exc:  # the folder's tables were removed since the run was read
                raise ConfigError(f"{exc}; the run's step table is gone from its folder") from None
        return pa.table({})

    @property
    def steps(self) -> pandas.DataFrame:
        """The per-step table as a pandas DataFrame, one row per step (predict or update)."""
        return self.table().to_pandas()

    def plot(self) -> Figure:
        """A matplotlib Figure of the run over time: position error (under its 3-sigma envelope),
        1-sigma position with the band of the per-axis sigmas, NEES with the chi-square 5-95 % band
        of 6 degrees of freedom, NIS with its band, entropy; the panels the run has columns for (a
        run without a truth has no error and no NEES). Log axes where the values span decades; the
        custody loss, if any, is marked. See :mod:`cistrack.studies.run_figure`."""
        from cistrack.studies.run_figure import plot_run

        return plot_run(self.steps, self.summary.to_dict(), self.run_id)

    def __repr__(self) -> str:
        where = f", directory={str(self.directory)!r}" if self.directory else ""
        return f"Run({self.run_id!r}, status={self.status!r}, verdict={self.verdict.kind!r}{where})"


def _setting_items(settings: Mapping[str, Any] | Iterable[str] | None) -> list[str]:
    """``{"filter.n_particles": 500, "filter": {"name": "ukf"}}`` or ``["duration_days=2"]`` as
    ``--set`` items (values in TOML syntax)."""
    if settings is None:
        return []
    if isinstance(settings, str):
        return [settings]
    if not isinstance(settings, (Mapping, list, tuple)) or \
            (not isinstance(settings, Mapping) and not all(isinstance(s, str) for s in settings)):
        raise TypeError(f"settings={settings!r}: give a mapping such as {{'filter.n_particles': 500}} or a list of "
                        "'TABLE.KEY=VALUE' strings")
    if not isinstance(settings, Mapping):
        return list(settings)
    items: list[str] = []

    def add(prefix: str, value: Any) -> None:
        if isinstance(value, Mapping):
            for k, v in value.items():
                add(f"{prefix}.{k}" if prefix else str(k), v)
            return
        plain = _plain_value(value)
        if isinstance(plain, float) and not math.isfinite(plain):
            raise ConfigError(f"settings[{prefix!r}] = {quoted(value)}: a setting must be a finite number")
        try:
            text = _inline_toml(plain)
        except TypeError:
            raise ConfigError(f"settings[{prefix!r}] = {quoted(value)}: not a setting value (give a number, string, "
                              "boolean, path, list or table)") from None
        items.append(f"{prefix}={text}")

    add("", settings)
    return items


def _inline_toml(value: Any) -> str:
    """``value`` in TOML syntax on one line: ``[1, 2]``, ``{t_days = 1.0, delta_v_ms = 0.5}`` (a
    list had been written over several lines, and messages quoted it with literal newlines).
    TypeError for a value TOML cannot hold."""
    import tomli_w

    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{tomli_w.dumps({str(k): 0}).rpartition(' = ')[0]} = {_inline_toml(v)}"
                               for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_inline_toml(v) for v in value) + "]"
    return tomli_w.dumps({"v": value}).partition("=")[2].strip()


_SET_ITEM = re.compile(r"--set ([A-Za-z_][\w-]*(?:\.[\w-]+)*)")


@contextmanager
def _python_words() -> Iterator[None]:
    """A ConfigError's message as the Python API's caller reads it: a ``--set KEY`` the command line
    would have been given names ``settings['KEY']``, and ``with --set`` says ``with settings`` (no
    --set was given: the settings came as an argument)."""
    try:
        yield
    except ConfigError as exc:
        text = _SET_ITEM.sub(lambda m: f"settings[{m.group(1)!r}]", str(exc)).replace("with --set)", "with settings)")
        if text == str(exc):
            raise
        raise type(exc)(text) from None


def _plain_value(value: Any) -> Any:
    """A setting's value as TOML can write it: a numpy scalar (``np.int64(500)``, ``np.float32(1.5)``)
    as the Python number it holds, a path (``os.PathLike``) as its string, inside lists too."""
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, (list, tuple)):
        return [_plain_value(v) for v in value]
    item = getattr(value, "item", None)
    if type(value).__module__ == "numpy" and callable(item) and getattr(value, "ndim", None) == 0:
        return item()
    return value


def load_scenario(scenario: str | Path | Scenario = DEFAULT_SCENARIO, *,
                  settings: Mapping[str, Any] | Iterable[str] | None = None,
                  registry: Registry | None = None) -> Scenario:
    """A validated scenario: a built-in name (``cistrack scenarios`` lists them), a TOML file, or a
    :class:`Scenario`, with ``settings`` applied exactly as ``--set`` applies them on the command line.

    ``settings``: ``{"filter.n_particles": 2000, "duration_days": 2}`` (dotted keys or nested
    dicts) or ``["filter.n_particles=2000"]``; a wrong key or value raises :class:`ConfigError`
    naming the table and key.
    """
    from cistrack.scenario.loading import Scenario
    from cistrack.scenario.loading import load_scenario as _load
    from cistrack.scenario.settings import apply_settings

    if not isinstance(scenario, (str, os.PathLike, Scenario)):
        raise TypeError(f"scenario={scenario!r}: give a built-in scenario name, a path to a TOML file "
                        "(str or pathlib.Path) or a Scenario from load_scenario")
    _checked_arguments(registry=registry)
    reg = registry or default_registry()
    scen = scenario if isinstance(scenario, Scenario) else _load(_expanded(scenario), reg)
    with _python_words():
        return apply_settings(scen, _setting_items(settings), reg)


def _checked_arguments(**given: Any) -> None:
    """TypeError naming the argument when ``out``, ``log``, ``registry``, ``directory``, ``study``,
    ``progress`` or ``overwrite`` has a type the API does not take, and ConfigError when a path
    (``out``, ``directory``, ``study``) is blank text (before anything is read or run)."""
    for name, value in given.items():
        if name in ("progress", "overwrite"):
            if not isinstance(value, bool):  # "no" would be true
                raise TypeError(f"{name}={value!r}: give True or False")
        elif name == "registry":
            if value is not None and not isinstance(value, Registry):
                raise TypeError(f"registry={value!r}: give a cistrack Registry (cistrack.api.default_registry() or "
                                "load_registry()), or None for the default one")
        elif name == "log":
            if value is not None and not callable(value):
                raise TypeError(f"log={value!r}: give a callable that takes one string, or None")
        elif not (isinstance(value, (str, os.PathLike)) or (value is None and name == "out")):
            allowed = "a path (str or pathlib.Path)" + (" or None" if name == "out" else "")
            raise TypeError(f"{name}={value!r}: give {allowed}")
        elif isinstance(value, str) and not value.strip():  # as the command's --out '': not the current folder
            raise ConfigError(f"{name}={value!r} is empty; give a path" + (", or leave out out (None) for the default"
                                                                             if name == "out" else ""))


def _expanded(path: Any) -> Any:
    """``path`` with a leading ``~`` or ``~user`` expanded, as the shell expands it on the command line
    (a str stays a str, a path becomes a Path); anything else as it is. ``out="~/x"`` had made a
    folder literally named ``~`` in the current directory."""
    if isinstance(path, str):
        return os.path.expanduser(path)
    if isinstance(path, os.PathLike):
        return Path(os.path.expanduser(os.fspath(path)))
    return path


def run(scenario: str | Path | Scenario = DEFAULT_SCENARIO, *, seed: int | None = None,
        settings: Mapping[str, Any] | Iterable[str] | None = None, out: str | Path | None = None,
        progress: bool = False, log: Callable[[str], None] | None = None, observers: Iterable[Any] = (),
        registry: Registry | None = None, overwrite: bool = False) -> Run:
    """Run one scenario end to end, as ``cistrack run`` does, and return its :class:`Run`.

    Parameters
    ----------
    scenario : str, Path or Scenario
        A built-in scenario name, a TOML file, or a scenario from :func:`load_scenario`.
    seed : int, optional
        The run's seed (default: the scenario's). The same scenario and seed give the same numbers.
    settings : mapping or list of str, optional
        Overrides, as for :func:`load_scenario`.
    out : path, optional
        Write the results folder here (a new or empty folder, as ``cistrack run --out``); by default
        the run is kept in memory only. As for ``cistrack run``, the folder is locked while the run
        writes (another process writing there raises at once), and a folder holding the results
        of another scenario, other settings or another seed is refused (ConfigError naming what is
        there) unless ``overwrite``; the same run again replaces its own results.
    progress : bool
        Show a progress bar on stderr.
    log : callable, optional
        Receives one string per stage of the run ("reading measurements ...", "IOD ...").
    observers : iterable
        Extra lifecycle-hook observers (for example a rerun recorder from the registry).
    overwrite : bool
        Replace the results of another run in ``out`` (see ``out``).
    """
    from cistrack.results.output_paths import check_output_dir
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.limits import check_seed

    from cistrack.runs.observers import checked_observers

    observers = checked_observers(observers, "observers")
    _checked_arguments(out=out, log=log, registry=registry, progress=progress, overwrite=overwrite)
    reg = registry or default_registry()
    scen = load_scenario(scenario, settings=settings, registry=reg)
    seed = scen.seed if seed is None else check_seed(seed, "seed")
    if out is None:
        res = run_scenario(scen, seed=seed, registry=reg, observers=observers, progress=progress, log=log)
        return Run(res.summary, None, tuple(res.rows))
    from cistrack.results.dir_lock import run_lock
    from cistrack.results.earlier_run import PYTHON_WORDS, check_replacing, clear_replaced_fit

    directory = _expanded(Path(out))
    check_output_dir(directory, "out")
    with run_lock(directory, "out"):  # one run at a time in a results directory, as cistrack run
        if check_replacing(directory, scen, seed, "out", overwrite=overwrite, words=PYTHON_WORDS):
            clear_replaced_fit(directory)
        res = run_scenario(scen, seed=seed, registry=reg, observers=observers, output_dir=directory,
                           progress=progress, log=log, residual_figure=True)
    return Run(res.summary, directory, tuple(res.rows))


def fit(files: str | Path | Iterable[str | Path], *, settings: Mapping[str, Any] | Iterable[str] | None = None,
        out: str | Path | None = None, progress: bool = True, log: Callable[[str], None] | None = None,
        registry: Registry | None = None, overwrite: bool = False) -> list[ObjectFit]:
    """Fit an orbit to each object in observation ``files`` (one path or several), as ``cistrack fit``
    does (docs/real-data.md), and return one :class:`ObjectFit` per object, in order of first
    appearance (``.designation``, ``.ok``, ``.result``: the :class:`cistrack.least_squares.FitResult`
    with the state (6,) and covariance (6, 6) at the fit epoch, synodic LU and VU; ``.directory``).

    ``settings``: as for :func:`run`, plus ``fit.*`` and ``measurements.reader.*``. ``out``: the
    results folder (default ``runs/fit-<designation>``; with several objects, one folder each
    under it). ``progress``: progress on stderr (default), as ``cistrack fit`` shows it: a line per
    stage and the filter's progress bar; False is silent, as ``--quiet``. ``log``: receives the
    stage lines instead of stderr. ``registry``: the components to use (default: the installed plugins).
    ``overwrite``: replace a run's results or another object's fit in ``out`` (refused otherwise, as
    ``cistrack fit`` refuses without ``--overwrite``; an earlier fit of the same object is redone).
    """
    from cistrack.fitting.from_observations import fit_files
    from cistrack.results.earlier_run import PYTHON_WORDS

    _checked_arguments(out=out, log=log, registry=registry, progress=progress, overwrite=overwrite)
    paths = _fit_paths(files)
    with _python_words():
        return fit_files([_expanded(p) for p in paths], out=_expanded(out), settings=_setting_items(settings),
                         registry=registry, log=log, progress=progress, overwrite=overwrite, words=PYTHON_WORDS)


def _fit_paths(files: Any) -> list:
    """``files`` of :func:`fit` as a list of paths: one path, or any iterable of them (a list, a
    generator, a numpy array of strings: the signature's ``Iterable``, which had been refused for
    all but a list or tuple, probe J9); TypeError for anything else or none."""
    if isinstance(files, (str, os.PathLike)):
        return [files]
    paths = None
    if isinstance(files, Iterable) and not isinstance(files, (bytes, bytearray, Mapping)):
        try:
            paths = list(files)
        except TypeError:  # a 0-d numpy array says it is iterable, and is not
            paths = None
    if not paths or not all(isinstance(p, (str, os.PathLike)) for p in paths):
        raise TypeError(f"files={files!r}: give a path (str or pathlib.Path) or a non-empty iterable of paths "
                        "(a list, a tuple, a generator)")
    return paths


def _what_it_holds(d: Path) -> str:
    """For a folder without a run's manifest: what it holds instead, in words ("" when nothing
    cistrack wrote): the fits of several objects (read_run of each ``fit-*`` folder) or a study's
    runs."""
    from cistrack.results.output_paths import fit_folders_inside

    fits = fit_folders_inside(d, "fit-*")
    if fits:
        return (f"; it holds the fits of several objects, one folder each ({', '.join(fits[:4])}"
                f"{' ...' if len(fits) > 4 else ''}): read_run one of those, e.g. read_run({str(d / fits[0])!r})")
    if (d / "study.json").is_file():
        return "; it holds a study's runs (study.json): read_run one of its runs' folders, or ct.study for the study"
    return ""


def read_run(directory: str | Path) -> Run:
    """A finished (or interrupted) run read back from its results folder."""
    from cistrack.evaluation.run_summary import RunSummary
    from cistrack.results.store import read_manifest

    _checked_arguments(directory=directory)
    d = _expanded(Path(directory))
    if not d.is_dir():
        raise ConfigError(f"{d}: not a run's results folder ({'a file' if d.exists() else 'no such directory'})")
    try:
        manifest = read_manifest(d)
    except FileNotFoundError:
        raise ConfigError(f"{d}: not a run's results folder (no manifest.json){_what_it_holds(d)}") from None
    except ValueError as exc:  # truncated, or not JSON
        raise ConfigError(f"{d}/manifest.json: cannot be read ({exc}); not a manifest cistrack finished writing") from None
    _check_status(d, manifest.get("status"))
    summary = manifest.get("summary")
    if not isinstance(summary, dict):
        raise ConfigError(f"{d}/manifest.json: holds no run summary (the run was killed, or is still running, before "
                          "it wrote one); the steps it wrote stay readable with "
                          "cistrack.results.store.read_steps(DIRECTORY), and 'cistrack export --force' exports its "
                          "last estimate")
    try:
        return Run(RunSummary.from_dict(summary), d)
    except ValueError as exc:  # a damaged summary: no run_id, a seed that is not a number
        raise ConfigError(f"{d}/manifest.json: {exc}; not a manifest cistrack wrote") from None


def read_fit(directory: str | Path) -> dict[str, Any]:
    """The orbit fit read back from a ``cistrack fit`` results folder: its ``fit.json`` as a dict
    (``converged``, ``epoch_utc``, ``state_km`` (6,) km and km/s and ``covariance_km`` (6, 6) in the
    frame ``frame``, ``rms``, ``maneuvers``, ``area_to_mass``, ``messages``, ...; docs/real-data.md),
    checked as ``cistrack export`` and ``predict`` check it; undefined numbers are NaN. A folder of
    several objects' fits names them; ``read_run`` reads the filter run the fit started from."""
    from cistrack.fitting.fit_record import FIT_RECORD, read_fit_record
    from cistrack.results.output_paths import fit_folders_inside

    _checked_arguments(directory=directory)
    d = _expanded(Path(directory))
    if not d.is_dir():
        raise ConfigError(f"{d}: not a fit's results folder ({'a file' if d.exists() else 'no such directory'})")
    if not (d / FIT_RECORD).is_file():
        fits = fit_folders_inside(d, "fit-*")
        if fits:
            raise ConfigError(f"{d}: holds the fits of several objects, one folder each ({', '.join(fits[:4])}"
                              f"{' ...' if len(fits) > 4 else ''}): read_fit one of those, e.g. "
                              f"read_fit({str(d / fits[0])!r})")
    return read_fit_record(d)


def _check_status(d: Path, status: Any) -> None:
    """ConfigError unless ``status``, a manifest's, is one a run writes (as ``cistrack export``
    refuses a run whose status is missing or unknown)."""
    from cistrack.results.run_status import RUN_STATUSES

    if status not in RUN_STATUSES:
        raise ConfigError(f"{d}/manifest.json: its status is {status!r}, not one a run writes "
                          f"({', '.join(RUN_STATUSES)}); not a manifest cistrack finished writing")


@dataclass(frozen=True)
class StudyResult:
    """A study's finished runs: ``name``; ``directory``, the study folder (``cistrack study report``
    on it writes the full report); ``runs``, a :class:`Run` per run done on disk (``.steps`` reads
    its table); ``rows``, their :attr:`table` rows (:mod:`cistrack.studies.study_table`);
    ``problems``, (run id, why) of each run that did not finish."""

    name: str
    directory: Path
    runs: tuple[Run, ...] = ()
    rows: tuple[dict[str, Any], ...] = field(default=(), repr=False)
    problems: tuple[tuple[str, str], ...] = ()

    @property
    def summaries(self) -> list[RunSummary]:
        """Each run's summary, in the order of :attr:`runs`."""
        return [r.summary for r in self.runs]

    @property
    def table(self) -> pandas.DataFrame:
        """One row per run: scenario, filter, iod, seed, run_id, status, verdict, reason,
        custody_kept, the final metrics (km, m/s, cm/s, NEES, entropy) and wall_time_s."""
        import pandas as pd

        return pd.DataFrame([{k: v for k, v in row.items() if k not in ("summary", "directory")} for row in self.rows])

    def plot(self) -> Figure:
        """A matplotlib Figure: per filter, IOD and scenario the median over seeds and the 5-95 %
        band of position error, 1-sigma position, NEES (with its chi-square band) and entropy (see
        :mod:`cistrack.studies.study_figure`; ``cistrack study report`` writes the full figures)."""
        from cistrack.studies.study_figure import plot_study_groups

        varying = [k for k in ("filter", "iod", "scenario") if len({row[k] for row in self.rows}) > 1] or ["filter"]
        groups: dict[str, dict[str, list[Any]]] = {}
        for row, r in zip(self.rows, self.runs):
            g = groups.setdefault(" / ".join(str(row[k]) for k in varying), {"steps": [], "summaries": []})
            g["steps"].append(r.steps)
            g["summaries"].append(row["summary"])
        return plot_study_groups(groups, f"study {self.name}: {len(self.runs)} runs")

    def __repr__(self) -> str:
        kinds = [r.verdict.kind for r in self.runs]
        counts = ", ".join(f"{kinds.count(k)} {k}" for k in dict.fromkeys(kinds))
        return f"StudyResult({self.name!r}, {len(self.runs)} runs: {counts or 'none'}, directory={str(self.directory)!r})"


def _checked_study_counts(n_seeds: Any, first_seed: Any, workers: Any) -> None:
    """Refuse :func:`study`'s counts by their keyword names (the study's own checks name the
    command line's options)."""
    from cistrack.scenario.limits import check_count, check_seed

    if n_seeds is not None:
        check_count(n_seeds, "n_seeds", 1, 1_000_000)
    if first_seed is not None:
        check_seed(first_seed, "first_seed")
    if workers is not None:
        check_count(workers, "workers", 1, 1024)


def study(study: str | Path, *, n_seeds: int | None = None, first_seed: int | None = None,
          settings: Mapping[str, Any] | Iterable[str] | None = None, out: str | Path | None = None,
          workers: int | None = None, progress: bool = False, log: Callable[[str], None] | None = None,
          overwrite: bool = False) -> StudyResult:
    """Run every missing run of a study, as ``cistrack study run`` does, and return its :class:`StudyResult`.

    ``study``: a built-in study name (``cistrack scenarios``), a study TOML file or a study folder.
    ``n_seeds``, ``first_seed``: these seeds instead of the file's (``--n-seeds``, ``--first-seed``).
    ``settings``: overrides of every run, as for :func:`load_scenario` (``--set``; the default
    folder then names their hash). ``out``: the study folder (default ``studies_out/<name>``);
    runs already done there are not run again. ``workers``: local processes (default: one per
    core). ``progress``: a progress bar on stderr. ``log``: receives the line ``cistrack study run``
    prints when the study ends (runs completed, already done, failed; the folder). Lost runs
    raise (none finished) or warn. ``overwrite``: run again the finished runs in ``out`` that the
    study now plans otherwise (another scenario, settings, seed or input file), replacing their
    results (a ConfigError naming them otherwise, as ``cistrack study run`` without ``--overwrite``).
    """
    from cistrack.evaluation.run_summary import RunSummary
    from cistrack.studies.lost_runs import say_lost_runs
    from cistrack.studies.study import done_line, run_study
    from cistrack.studies.study_table import study_rows

    _checked_arguments(study=study, out=out, log=log, progress=progress, overwrite=overwrite)
    _checked_study_counts(n_seeds, first_seed, workers)
    items = _setting_items(settings) or None
    with _python_words():
        res = run_study(_expanded(study), out_dir=_expanded(out), workers=workers, progress=progress, settings=items,
                        first_seed=first_seed, n_seeds=n_seeds, overwrite=overwrite)
    if log is not None:
        log(done_line(res))
    specs, directory = res["specs"], Path(res["out_dir"])
    rows = study_rows(specs)
    runs = tuple(Run(RunSummary.from_dict(row["summary"]), Path(row["directory"])) for row in rows)
    problems = say_lost_runs(str(res["name"]), directory, len(specs), len(runs), res.get("problems"))
    return StudyResult(str(res["name"]), directory, runs, tuple(rows), problems)
