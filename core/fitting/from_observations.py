"""``cistrack fit``: observation files in, a least-squares orbit per object out.

For each object in the files (:mod:`cistrack.fitting.observation_input`):

1. a scenario is built in memory from the template ``cistrack/scenarios/fit-defaults.toml``
   (ephemeris dynamics, ``real-telescope`` RA/Dec, the speed-bounded uniform-range IOD, the
   PGM) with the data's epoch (the whole minute at least :data:`EPOCH_LEAD_MINUTES` before the
   first observation), span (to the last observation plus :data:`SPAN_MARGIN_HOURS`) and
   observation file (the merged observations, written into the results directory), then the
   ``--set`` items; it runs through :func:`cistrack.runs.pipeline.run_scenario`, which writes
   the usual results files;
2. the filter's final estimate is propagated to the fit epoch and refined by
   :func:`cistrack.least_squares.fit_orbit` over the whole arc, without a prior by default (the
   filter's covariance comes from the same observations: as a prior it would count them twice);
   ``--set fit.prior=filter`` uses it anyway. By default the filter runs over the first hours
   only (:mod:`cistrack.fitting.early_seed`; their observations in :data:`EARLY_FILE`), and over
   every observation when the least squares from there does not give a clean fit
   (``--set fit.filter_span=all``: always);
3. ``fit.json``, ``residuals.csv`` and a residual plot per site are written
   (:mod:`cistrack.fitting.fit_record`, :mod:`cistrack.fitting.residual_plots`).

When that cannot start (the first pass is too short for the template's kinematic IOD: a lone
tracklet of 3-5 exposures) or its least squares fails, the fit falls back on the IOD
:data:`RANGING_IOD` (systematic ranging over a tracklet's admissible region, scored on the next
tracklets, the least squares extended over the whole arc: ``cistrack.plugins.iod.tracklet_ranging``)
with ``arc = "all"``: its cloud lies at the last observation, the filter has nothing left to do, and
the least squares starts from the IOD's orbit. The fit's messages say which observations seeded it,
by which method and why (:func:`seeding_text`); a fit of less than a day of observations says in
words that the orbit is poorly determined. Observations that are one lone tracklet (one site, at
most two hours) determine no orbit: nothing runs, and ``ObjectFit.undetermined`` says so with the
tracklet's sky motion and admissible region (:func:`cistrack.fitting.determination.lone_tracklet_report`).

The fit epoch is the last observation by default (``--set fit.epoch=middle|first``): measured on
the shipped example (65 observations, 6 days, ephemeris dynamics) the unit-diagonal normal matrix
has condition number 446 there, 2,815 in the middle of the arc and 836 at its start, and the
estimate there is the one a prediction starts from. All three give the same orbit.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field, replace
from datetime import timedelta
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, ConfigError, PropagationError, clipped, quoted
from cistrack.fitting.fit_record_check import MAX_DISTANCE_KM, MAX_SPEED_KMS
from cistrack.fitting.lov_solutions import AUTO_DELTA_CHI2
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.result import sigma_factor
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.fitting.maneuver_search import add_maneuvers
from cistrack.fitting.arcs import ArcSettings, arc_settings
from cistrack.fitting.observation_input import (READ_EPOCH, ObjectObservations, copies_read_quietly, data_kind, distinct_names,
                                                read_object_observations, write_merged)
from cistrack.least_squares.options import FitOptions, fit_option_problem
from cistrack.least_squares.progress import reported_to
from cistrack.least_squares.result import FitResult
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.plugin.registry import Registry, default_registry
from cistrack.fitting.fit_replacing import (FIT_RECORD, check_fit_form, check_fit_replacing, check_several_objects_dir,
                                            remove_other_form)
from cistrack.results.earlier_run import CLI_WORDS, OptionWords
from cistrack.results.dir_lock import fit_lock
from cistrack.results.output_paths import check_output_dir, distinct_stems
from cistrack.results.store import MANIFEST
from cistrack.scenario.builtin_scenarios import builtin_scenario_path
from cistrack.scenario.loading import Scenario, load_scenario, parse_scenario
from cistrack.scenario.settings import merge_settings, parse_settings
from cistrack.threads import library_thread_limit

__all__ = ["fit_files", "ObjectFit", "FitChoices", "fit_choices", "TEMPLATE", "EPOCH_LEAD_MINUTES",
           "SPAN_MARGIN_HOURS", "RANGING_IOD", "SHORT_ARC_HOURS", "seeding_text"]

TEMPLATE = "fit-defaults"
"""The built-in scenario whose tables are the defaults of ``cistrack fit``."""
EPOCH_LEAD_MINUTES = 30
"""The scenario epoch is the whole minute at least this long before the first observation."""
SPAN_MARGIN_HOURS = 2.0
"""The scenario's span ends this long after the last observation."""
RANGING_IOD = "tracklet-ranging"
"""The IOD the fit falls back on when the template's cannot start or its fit fails."""
SEEDED_ITERATIONS = 200
"""Levenberg-Marquardt iterations per pass, at least, of the least squares started from the ranging
IOD's orbit."""
SEEDED_REJECT_FRACTION = 0.1
"""At most this share of the observations is rejected by the least squares started from the ranging
IOD's orbit, unless ``--set fit.max_reject_fraction`` gives the share (:func:`seeded_reject_fraction`)."""
SHORT_ARC_HOURS = 24.0
"""A fit over observations spanning less than this says that the orbit is poorly determined."""
_EPOCHS = ("last", "middle", "first")
_PRIORS = ("none", "filter")
_FILTER_SPANS = ("early", "all")
EARLY_FILE = "observations-early"
"""The observations the filter ran over when it took the first hours only (:mod:`.early_seed`),
written beside ``observations.psv`` (the run's ``scenario.toml`` names it)."""


def __getattr__(name: str) -> Any:
    """``AUTO_LOV_SIGMAS`` (3.0, the default line's old reach) with a DeprecationWarning, until the
    next release: the default line now runs until the data rule it out (:mod:`.lov_solutions`)."""
    if name == "AUTO_LOV_SIGMAS":
        warnings.warn("cistrack.fitting.from_observations.AUTO_LOV_SIGMAS no longer sets the default line of variations, "
                      "which now runs until its chi-square has risen by cistrack.fitting.lov_solutions.AUTO_DELTA_CHI2; "
                      "the old value 3.0 is kept, with this warning, until the next release",
                      DeprecationWarning, stacklevel=2)
        return 3.0
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class FitChoices:
    """The ``[fit]`` settings: ``epoch`` ("last", "middle" or "first" observation), ``prior``
    ("none" or "filter"), the :class:`FitOptions` of the least squares and ``lov`` (sigmas: the
    line of variations out to that many sigmas each side, every half sigma; 0 = none; None, the
    default "auto": when the fit is poorly determined, until the data rule the line out,
    :mod:`.lov_solutions`, else none) and
    ``filter_span`` ("early": the least squares starts from the filter run over the first
    hours only when that fit is clean, :mod:`cistrack.fitting.early_seed`; "all": the filter
    runs over every observation)."""

    epoch: str = "last"
    prior: str = "none"
    options: FitOptions = field(default_factory=FitOptions)
    lov: float | None = None
    arcs: ArcSettings = field(default_factory=ArcSettings)
    filter_span: str = "early"
    reject_fraction_set: bool = False
    """Whether ``fit.max_reject_fraction`` was set (then it applies everywhere, the least squares
    from the ranging IOD's orbit included: :func:`seeded_reject_fraction`)."""


def seeded_reject_fraction(choices: FitChoices) -> float:
    """The share of the observations the least squares started from the ranging IOD's orbit rejects
    at most: the ``fit.max_reject_fraction`` set, else its default capped at
    :data:`SEEDED_REJECT_FRACTION`. (The cap had held a setting above it too, while the fit's note
    named the setting as the way to reject more: probe I5.)"""
    if choices.reject_fraction_set:
        return choices.options.max_reject_fraction
    return min(choices.options.max_reject_fraction, SEEDED_REJECT_FRACTION)


def fit_choices(table: dict[str, Any]) -> FitChoices:
    """The ``fit.*`` settings (``--set fit.KEY=VALUE``) checked; ConfigError naming the key."""
    if not isinstance(table, dict):
        raise ConfigError("--set fit=...: 'fit' is a table; set its keys, e.g. --set fit.epoch=middle")
    arcs, opts = arc_settings(dict(table))
    opts.setdefault("area_to_mass", "auto")  # C_R A/m where the arc supports it (cistrack.least_squares.area_to_mass)
    epoch = opts.pop("epoch", "last")
    prior = opts.pop("prior", "none")
    lov = opts.pop("lov", "auto")
    span = opts.pop("filter_span", "early")
    if span not in _FILTER_SPANS:
        raise ConfigError(f"--set fit.filter_span={quoted(span)}: must be 'early' (default: the filter over the "
                          "first half day seeds the least squares when that fit is clean) or 'all' (the filter over "
                          "every observation)")
    if lov != "auto" and (isinstance(lov, bool) or not isinstance(lov, (int, float))
                          or not (lov == 0 or 0.5 <= lov <= 20)):
        raise ConfigError(f"--set fit.lov={quoted(lov)}: must be 'auto' (default: when the fit is poorly "
                          f"determined, until the chi-square has risen by {AUTO_DELTA_CHI2:g}), 0 (none) or a number of "
                          "sigmas from 0.5 to 20 (the line of variations out to that many sigmas each side)")
    if epoch not in _EPOCHS:
        shown = epoch.isoformat() if hasattr(epoch, "isoformat") else quoted(epoch)  # a TOML date as typed
        raise ConfigError(f"--set fit.epoch={shown}: must be one of {', '.join(_EPOCHS)} (the observation "
                          "at which the state is estimated; the fit's epoch is not a date)")
    if prior not in _PRIORS:
        raise ConfigError(f"--set fit.prior={quoted(prior)}: must be 'none' (default) or 'filter' (the filter's "
                          "final covariance as a prior)")
    known = set(FitOptions.__dataclass_fields__)
    unknown = sorted(set(opts) - known)
    if unknown:
        raise ConfigError(f"--set fit.{unknown[0]}: unknown fit setting; known: epoch, prior, lov, filter_span, arcs, arc_gap_days, link_gap_days, "
                          + ", ".join(sorted(known)))
    for key, value in opts.items():
        why = fit_option_problem(key, value)
        if why:
            raise ConfigError(f"--set fit.{key}={value!r}: {why}")
    damping = FitOptions(**{k: v for k, v in opts.items() if k in ("damping", "max_damping")})
    if damping.max_damping <= damping.damping:
        raise ConfigError(f"--set fit.max_damping={damping.max_damping!r}: must exceed fit.damping "
                          f"({damping.damping!r}): the iteration stops once the damping passes it, so it would stop "
                          "before its first step")
    return FitChoices(epoch, prior, FitOptions(**opts), None if lov == "auto" else float(lov), arcs, span,
                      "max_reject_fraction" in opts)


@dataclass
class ObjectFit:
    """The outcome for one object.

    Attributes
    ----------
    designation : str           the object's designation in the files
    directory : Path            its results directory
    scenario : Scenario         the scenario the filter ran (epoch = t 0 of every TU time)
    run : Any                   the filter run (:class:`cistrack.runs.pipeline.RunResult`), or None
    result : FitResult or None  the least-squares fit (None when it could not be made)
    failure : str               why there is no fit, or why the fit made is not reported as
                                converged (:func:`cistrack.fitting.fit_record.unsound_reason`: "not
                                a clean fit: ...", "the least squares did not converge (...)"); ""
                                for a converged fit (its own messages are in ``result``)
    notes : list of str         the files and their weights
    lov : list of LovPoint      the line of variations (``--set fit.lov=N``), or empty
    start : str                 "" when the least squares started from the filter's final
                                estimate; else the earlier filter estimate it restarted from, and why
    seeding : dict              which observations seeded the fit, by which method and why:
                                "method" (the IOD), "rows" (indices into the observations, time
                                order), "why" (str); empty when no IOD ran
    arcs : ArcFit or None       the arcs left out and their residual ladder (:mod:`.fit_findings`)
    determination : Determination or None  how well the orbit is determined, in words
    events : list of OrbitEvent or None    impacts and closest approaches after the fit epoch
    burn_sensitivity : list of GapSensitivity or None   the largest burn each gap between observing
                                sessions would hide (:mod:`cistrack.least_squares.burn_sensitivity`)
    undetermined : dict         for observations that cannot determine an orbit (one lone
                                tracklet): why, in words, and what they give (the tracklet's place
                                and rates on the sky, the admissible region's ranges and range
                                rates; :func:`cistrack.fitting.determination.lone_tracklet_report`);
                                empty otherwise
    filter_rows : int           how many of the first observations the filter ran over when it
                                took the first hours only (:mod:`.early_seed`); 0: all of them
    searched : bool             the burn search was made and its burns kept while seeding
                                (:func:`_burns_explain`): it is not made again
    reject_fraction : float or None  the share of the observations the fit's least squares could
                                reject at most, when not ``choices.options.max_reject_fraction``
                                (from the ranging IOD's orbit: :func:`seeded_reject_fraction`)
    """

    designation: str
    directory: Path
    scenario: Scenario | None
    run: Any = None
    result: FitResult | None = None
    failure: str = ""
    notes: list[str] = field(default_factory=list)
    choices: FitChoices = field(default_factory=FitChoices)
    lov: list = field(default_factory=list)
    start: str = ""
    seeding: dict = field(default_factory=dict)
    arcs: Any = None
    determination: Any = None
    events: Any = None
    burn_sensitivity: Any = None
    undetermined: dict = field(default_factory=dict)
    filter_rows: int = 0
    searched: bool = False
    reject_fraction: float | None = None

    @property
    def ok(self) -> bool:
        """A fit was made and converged."""
        return self.result is not None and self.result.converged

    def __repr__(self) -> str:
        """A few lines: the object, its outcome, the method, the observations used and rejected,
        the weighted RMS and the fit epoch (:meth:`report` for the full summary)."""
        from cistrack.fitting.fit_summary import short_lines

        return "\n".join(short_lines(self))

    def report(self) -> str:
        """The full summary, as ``cistrack fit`` prints it: outcome, how well the orbit is
        determined, noise, sigmas at the fit epoch, the line of variations, events, every warning."""
        from cistrack.fitting.fit_summary import summary_lines

        return "\n".join(summary_lines(self))


def _slug(designation: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_.-]+", "_", designation.strip()).strip("._") or "object"
    return s[:64]


def _directory_names(designations: list[str]) -> list[str]:
    """``fit-<slug>`` for each designation; designations whose slugs coincide (``2026 AB`` and
    ``2026/AB``; letter case counts as the same, as on a case-insensitive file system) each get
    a short hash of the designation appended, so that no object's fit lands in another's directory."""
    stems = distinct_stems(designations, lambda d: f"fit-{_slug(d)}")
    return [stems[d] for d in designations]


def _split_settings(items: Iterable[str] | None) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(scenario settings, fit settings, reader parameters) from ``--set`` items."""
    settings = parse_settings(items)
    fixed = sorted(k for k in ("epoch", "duration_days", "name") if k in settings)
    if fixed:
        raise ConfigError(f"--set {fixed[0]}: cistrack fit sets the scenario's epoch, duration_days and name from "
                          "the observations (epoch: 30 min before the first, duration: to past the last); "
                          "fit.epoch=first|middle|last chooses where the state is estimated")
    if isinstance(settings.get("sensor"), dict) and "measurement" in settings["sensor"]:
        raise ConfigError(f"--set sensor.measurement={quoted(settings['sensor']['measurement'])}: cistrack fit sets what "
                          "the sensor measures from the observations themselves (RA/Dec or azimuth/elevation, as the "
                          "files give them)")
    unused = sorted(k for k in ("truth", "schedule") if k in settings)
    if unused:
        raise ConfigError(f"--set {unused[0]}.*: cistrack fit simulates nothing, so [{unused[0]}] (a simulated "
                          "truth, or the schedule of simulated measurements) is not used; the observations come "
                          "from the files")
    fit_table = settings.pop("fit", {})
    meas = settings.pop("measurements", {})
    if not isinstance(meas, dict) or set(meas) - {"reader"}:
        raise ConfigError("--set measurements.*: only measurements.reader.KEY (e.g. "
                          "measurements.reader.sigma_arcsec=0.5) can be set; the observation files are the "
                          "command's arguments")
    reader = meas.get("reader", {})
    if isinstance(reader, str):
        reader = {"name": reader}
    if not isinstance(reader, dict):
        raise ConfigError("--set measurements.reader=...: give reader keys, e.g. measurements.reader.sigma_arcsec=0.5")
    return settings, fit_table, reader


def _data_span(obs: ObjectObservations) -> tuple[str, float]:
    """(scenario epoch UTC text, duration in days) for the object's observations."""
    base = units.parse_utc(READ_EPOCH)
    first = units.tu_to_utc(base, float(obs.measurements.times[0]))
    last = units.tu_to_utc(base, float(obs.measurements.times[-1]))
    start = (first - timedelta(minutes=EPOCH_LEAD_MINUTES)).replace(second=0, microsecond=0)
    days = (last - start).total_seconds() / 86400.0 + SPAN_MARGIN_HOURS / 24.0
    return units.format_utc(start), math.ceil(days * 1e4) / 1e4


def _check_range_used(choices: FitChoices, obs: ObjectObservations) -> None:
    """ConfigError when ``fit.use_range`` is asked of observations that measure no range."""
    if choices.options.use_range and "range" not in tuple(obs.measurements.names):
        raise ConfigError(f"--set fit.use_range=true: the observations of {clipped(obs.designation)} "
                          f"({', '.join(distinct_names(obs.files))}) measure no range, so there is none to use")


def _checked_scenario(obs: ObjectObservations, obs_file: Path, settings: dict[str, Any],
                      registry: Registry, choices: FitChoices | None = None) -> Scenario:
    """:func:`_scenario`, whose refusal of the epoch the observations set (e.g. outside the
    ephemeris' years) names the files and the observations' span: the data, not a setting, is at
    fault; with ``choices``, the fit settings checked against the observations too."""
    if choices is not None:
        _check_range_used(choices, obs)
    try:
        scen = _scenario(obs, obs_file, settings, registry)
        _scenario(_last_observation(obs), obs_file, settings, registry)  # the arc's end inside those years too
        return scen
    except ConfigError as exc:
        if "'epoch'" not in str(exc):
            raise
        epoch, days = _data_span(obs)
        base = units.parse_utc(READ_EPOCH)
        first, last = (units.format_utc(units.tu_to_utc(base, float(t)))
                       for t in (obs.measurements.times[0], obs.measurements.times[-1]))
        # the observations' own dates, not the scenario's epoch (30 minutes before the first): a file
        # whose first observation is 1900-01-01T00:00 had been said to start 1899-12-31 (probe I4)
        raise ConfigError(f"{', '.join(str(f) for f in obs.files)}: the observations of {clipped(obs.designation)} "
                          f"run from {first} to {last} ({days:.3g} d with the fit's margins; its epoch "
                          f"{epoch} lies {EPOCH_LEAD_MINUTES:g} minutes before the first), which the fit "
                          f"cannot model: {exc}") from None


_OWN_READERS = {".psv": "ades-psv", ".tdm": "tdm"}
"""The reader of the fit's own copy of the observations, by the suffix it was written with: named,
so that a third party's reader claiming the same suffix cannot make the copy ambiguous. It reads
the copy with ``check_degrees = false``: the user's files were checked (or not, as the user chose)
when they were read, and a copy of angles near RA 0 and the equator is degrees as written."""


def _scenario(obs: ObjectObservations, obs_file: Path, settings: dict[str, Any], registry: Registry,
              early: bool = False) -> Scenario:
    """The template's scenario for ``obs`` (read from ``obs_file``) with ``settings``; ``early``:
    the filter over the first hours, with at most :data:`.early_seed.EARLY_PARTICLES` particles."""
    template = load_scenario(TEMPLATE, registry)
    epoch, days = _data_span(obs)
    raw = dict(template.raw)
    raw.update({"name": f"fit-{_slug(obs.designation)}", "epoch": epoch, "duration_days": days,
                "description": f"cistrack fit of {clipped(obs.designation)} from {', '.join(distinct_names(obs.files))}",
                "measurements": {"file": str(obs_file.resolve()),
                                 "reader": {"name": _OWN_READERS[obs_file.suffix], "check_degrees": False}}})
    raw["sensor"] = {**raw["sensor"], "measurement": data_kind(obs.measurements)}
    raw = _ranging_defaults(merge_settings(raw, settings))
    if early:
        from cistrack.fitting.early_seed import early_particles

        raw = early_particles(raw)
    return parse_scenario(raw, f"cistrack fit ({builtin_scenario_path(TEMPLATE).name} with --set)", registry)


def _ranging_defaults(raw: dict[str, Any]) -> dict[str, Any]:
    """``raw`` with the ranging IOD (when it is the scenario's) propagating with the scenario's
    dynamics and fitting the whole arc, unless the ``[iod]`` table says otherwise."""
    iod = raw.get("iod")
    if not (isinstance(iod, dict) and iod.get("name") == RANGING_IOD):
        return raw
    dyn = raw.get("dynamics", {})
    name = dyn.get("name") if isinstance(dyn, dict) else dyn
    return {**raw, "iod": {"dynamics": name, "arc": "all", **iod}}


def _ranging_scenario(scen: Scenario, registry: Registry) -> Scenario:
    """``scen`` with the IOD :data:`RANGING_IOD` (its defaults for a fit: :func:`_ranging_defaults`),
    as many particles as the template's IOD."""
    n = scen.raw.get("iod", {}).get("n_particles", 4000) if isinstance(scen.raw.get("iod"), dict) else 4000
    raw = _ranging_defaults({**scen.raw, "iod": {"name": RANGING_IOD, "n_particles": n}})
    return parse_scenario(raw, f"{scen.source} (IOD {RANGING_IOD})", registry)


def _fit_epoch(choice: str, times: np.ndarray) -> float:
    return float({"last": times[-1], "first": times[0], "middle": times[np.argmin(np.abs(times - 0.5 * (times[0] + times[-1])))]}[choice])


def _least_squares(ctx, choices: FitChoices, restart=None) -> FitResult:
    """The least-squares fit started from the filter's final estimate (ctx: the run's context), or
    from ``restart`` (a :class:`cistrack.fitting.restart.Restart`: an earlier estimate of the filter)."""
    belief = ctx.filter.belief
    what = "the filter's final estimate" if restart is None else f"the filter's estimate at {restart.utc}"
    if restart is None:
        mean = np.asarray(belief.mixture.mean, dtype=float)
        cov = np.asarray(belief.mixture.covariance, dtype=float)
        epoch = float(belief.epoch)
    else:
        mean, cov, epoch = restart.mean, restart.covariance, restart.t
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
        raise FitError(f"{what} is not finite; nothing to start the least squares from")
    ms = ctx.measurements
    t0 = _fit_epoch(choices.epoch, ms.times)
    try:
        start, stm = arc_states_and_stms(ctx.dynamics, mean, epoch, np.array([t0]))
    except PropagationError as exc:
        raise FitError(f"{what} cannot be propagated to the fit epoch: {exc}") from None
    prior = None
    if choices.prior == "filter":
        p = stm[0] @ cov @ stm[0].T
        prior = (start[0], 0.5 * (p + p.T))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnobservableWarning)  # also in the result's messages
        return fit_orbit(ctx.dynamics, ctx.sensor, ms, start[0], t0, prior=prior, options=choices.options)


def _fit_from_filter(ctx, choices: FitChoices, directory: Path) -> tuple[FitResult | None, str, str]:
    """(fit, failure, start): the least squares from the filter's final estimate; when that fails
    or does not converge, from the filter's estimate before the updates it should not have taken
    in (:func:`cistrack.fitting.restart.restart_points`), latest first. ``start`` says which estimate
    a restarted fit began from and why ("" for the final estimate)."""
    from cistrack.fitting.restart import restart_points

    try:
        result, failure = _least_squares(ctx, choices), ""
    except (FitError, PropagationError) as exc:
        result, failure = None, f"least squares: {exc}"
    if result is not None and result.converged:
        return result, "", ""
    for point in restart_points(directory):
        try:
            again = _least_squares(ctx, choices, point)
        except (FitError, PropagationError):
            continue
        if again.converged:
            first = failure.removeprefix("least squares: ") or "the least squares did not converge"
            return again, "", (f"the filter's estimate at {point.utc} (step {point.step}), {point.why}; "
                               f"from the filter's final estimate: {first}")
    return result, failure, ""


def _attempt(scen: Scenario, choices: FitChoices, directory: Path, registry: Registry, progress: bool,
             log: Callable[[str], None] | None, fallback: bool = False) -> tuple[Any, FitResult | None, str, str, bool]:
    """(run or None, fit or None, failure, start, seeded): the scenario run into ``directory``, then the
    least squares from the ranging IOD's orbit (``seeded``: :func:`_fit_from_iod`) or from the filter
    (:func:`_fit_from_filter`). ``fallback``: the scenario's IOD is the ranging IOD the fit fell back
    on, not the user's (its settings are set after choosing it)."""
    from cistrack.runs.pipeline import run_scenario

    try:
        run = run_scenario(scen, registry=registry, output_dir=directory, progress=progress,
                           log=(lambda m: log(f"  {m}")) if log else None)
    except CistrackError as exc:
        return (None, None, f"the filter run failed before its first step: {_iod_advice(exc, scen, registry, fallback)}",
                "", False)
    if log:
        log(f"  least squares over the {len(run.context.measurements)} observations")
    with reported_to(log):
        seeded = _fit_from_iod(run.context, choices)
        if seeded is not None:
            return run, seeded, "", "", True
        return (run, *_fit_from_filter(run.context, choices, directory), False)


def _iod_advice(exc: CistrackError, scen: Scenario, registry: Registry, fallback: bool) -> str:
    """``exc``'s message, and when it is the IOD's advising some of its parameters
    (:attr:`cistrack.errors.IODError.settings`), how ``cistrack fit`` sets them: ``--set
    iod.NAME=...`` (after ``--set iod.name=...`` for the IOD the fit fell back on), where the
    message names them as the ``[iod]`` keys of a scenario file."""
    from cistrack.errors import IODError
    from cistrack.interfaces.component import param_specs

    iod = scen.components["iod"].name
    own = param_specs(registry.get("iod", iod).factory) if isinstance(exc, IODError) else {}
    names = [n for n in getattr(exc, "settings", ()) if n in own]
    if not names:
        return str(exc)
    options = (f"--set iod.name={iod} " if fallback else "") + ", ".join(f"--set iod.{n}=..." for n in names)
    text = str(exc)
    return f"{text[:-1] if text.endswith('.') else text} (in cistrack fit: {options})" + "." * text.endswith(".")


def _attempt_early(one: ObjectFit, early: Scenario, registry: Registry, progress: bool,
                   log: Callable[[str], None] | None) -> tuple[Any, FitResult, str, str] | None:
    """(run, fit, "", "") from the filter run over the first hours (``early``, into the results
    directory; :mod:`cistrack.fitting.early_seed`), the least squares over all the observations of
    ``one.scenario`` from its final estimate; None when the run fails or the fit does not converge
    or looks like a maneuver (:func:`cistrack.least_squares.burn_search.suspicion`). The run's
    context then holds all the observations and their sensor; ``one.filter_rows`` is set."""
    from cistrack.fitting.early_seed import early_starts
    from cistrack.least_squares.burn_search import suspicion
    from cistrack.runs.pipeline import run_scenario
    from cistrack.runs.run_inputs import read_scenario_observations

    try:
        run = run_scenario(early, registry=registry, output_dir=one.directory, progress=progress,
                           log=(lambda m: log(f"  {m}")) if log else None)
        if run.summary.status != "finished":
            return None
        ms, sensor = read_scenario_observations(one.scenario, one.scenario.build("sensor", registry), registry,
                                                lambda m: None)
    except CistrackError:
        return None
    n_early = len(run.context.measurements)
    run.context.measurements, run.context.sensor = ms, sensor
    if log:
        log(f"  least squares over the {len(ms)} observations from the filter's estimate after the first {n_early}")
    suspect = None
    for start in early_starts(run.context.filter.belief):
        try:
            with reported_to(log):
                result = _least_squares(run.context, one.choices, start)
        except (FitError, PropagationError):
            continue
        if result.converged and not suspicion(result):
            one.filter_rows = n_early
            return run, result, "", ""
        suspect = suspect or (result if result.converged else None)
    if suspect is not None and _burns_explain(one, run, suspect, n_early, log):
        return run, one.result, "", ""
    if log:
        log("  no clean fit from there: the filter runs over every observation")
    return None


def _burns_explain(one: ObjectFit, run: Any, suspect: FitResult, n_early: int,
                   log: Callable[[str], None] | None) -> bool:
    """Whether impulsive burns explain ``suspect``, the least squares from the filter of the first
    hours that converged looking like a maneuver (:func:`add_maneuvers`): then ``one`` holds the fit
    with them (``one.searched``), and the filter need not run over every observation, which would
    seed the same search again (a dense three-site campaign with a 0.33 m/s burn: 40 of its 110
    seconds). Otherwise ``one`` is as it was."""
    one.run, one.result, one.filter_rows = run, suspect, n_early
    add_maneuvers(one, log or (lambda m: None))
    one.searched = bool(getattr(one, "maneuvers", None)) and one.ok
    if not one.searched:
        one.run, one.result, one.filter_rows, one.maneuvers, one.dynamics = None, None, 0, [], None
    return one.searched


def _early_scenario(obs: ObjectObservations, scen: Scenario, d: Path, job: _Job) -> Scenario | None:
    """The scenario of the filter over the first hours of ``obs`` (:func:`early_rows`; their file
    :data:`EARLY_FILE` written into ``d``), or None when the fit takes the full run: ``fit.filter_span
    = "all"``, a filter prior, the ranging IOD (it fits the whole arc itself) or too few later
    observations."""
    from dataclasses import replace

    from cistrack.fitting.early_seed import early_rows

    c = job.choices
    if c.filter_span != "early" or c.prior != "none" or scen.components["iod"].name == RANGING_IOD:
        return None
    t = np.asarray(obs.measurements.times, dtype=float)
    k = early_rows(np.sort(t))
    if k == 0:
        return None
    part = replace(obs, measurements=obs.measurements.subset(t <= np.sort(t)[k - 1]))
    suffix = write_merged(d / EARLY_FILE, part.measurements, obs.designation, job.registry)
    return _scenario(part, d / f"{EARLY_FILE}{suffix}", job.settings, job.registry, early=True)


def _fit_from_iod(ctx, choices: FitChoices) -> FitResult | None:
    """The least squares started from the ranging IOD's own orbit (its cloud's ``best_state`` and
    ``best_covariance`` at the cloud's epoch), or None when the IOD left none or that fit does not
    converge. The cloud's mean would do as well in most cases, but where the arc leaves a direction
    weakly determined the cloud spans thousands of km and its mean is a worse start."""
    from cistrack.fitting.restart import Restart

    meta = getattr(ctx.iod_cloud, "meta", None) or {}
    if meta.get("method") != RANGING_IOD or "best_state" not in meta:
        return None
    t = float(ctx.iod_cloud.epoch)
    start = Restart(0, units.format_utc(units.tu_to_utc(ctx.epoch, t)), t, np.asarray(meta["best_state"], dtype=float),
                    np.asarray(meta["best_covariance"], dtype=float), "the ranging IOD's orbit")
    from dataclasses import replace

    # From the IOD's orbit the first pass still holds the outliers the IOD rejected. With one of
    # them in, Levenberg-Marquardt can crawl (178 iterations measured on a 17-observation NRHO set):
    # at least SEEDED_ITERATIONS per pass; and on a weakly determined arc it pulls the first pass so
    # far that the robust threshold let whole clean tracklets go (10 of 23, 55 km off): at most
    # SEEDED_REJECT_FRACTION rejected, unless fit.max_reject_fraction says how many.
    opts = replace(choices.options, max_iterations=max(choices.options.max_iterations, SEEDED_ITERATIONS),
                   max_reject_fraction=seeded_reject_fraction(choices))
    try:
        result = _least_squares(ctx, replace(choices, options=opts), start)
    except (FitError, PropagationError):
        return None
    return result if result.converged else None


def _fit_object(one: ObjectFit, registry: Registry, progress: bool, log: Callable[[str], None] | None,
                early: Scenario | None = None) -> None:
    """Fill ``one`` (run, result, failure, start, seeding): the template's way first (with ``early``,
    the scenario of the first hours, its filter run seeding the least squares when that fit is
    clean: :func:`_attempt_early`); when it gives no converged fit, the ranging IOD
    (:data:`RANGING_IOD`), whose run replaces the first in the results directory (the first's
    failure is kept in the seeding's ``why``)."""
    say = log or (lambda m: None)
    attempt = _attempt_early(one, early, registry, progress, log) if early is not None else None
    if attempt is None and early is not None:
        Path(early.measurements_file).unlink(missing_ok=True)
    one.run, one.result, one.failure, one.start, seeded = (*attempt, False) if attempt else _attempt(
        one.scenario, one.choices, one.directory, registry, progress, log)
    first = ""
    if not one.ok and one.scenario.components["iod"].name != RANGING_IOD:
        first = one.failure or (one.result.messages[0] if one.result is not None else "no fit")
        say(f"{one.designation}: {first}; falling back on the IOD '{RANGING_IOD}'")
        one.scenario = _ranging_scenario(one.scenario, registry)
        one.run, one.result, one.failure, one.start, seeded = _attempt(one.scenario, one.choices, one.directory,
                                                                       registry, progress, log, fallback=True)
        if one.failure:
            one.failure += f" (before it, with the template's IOD: {first})"
    one.reject_fraction = seeded_reject_fraction(one.choices) if seeded else None
    if one.start:
        say(f"{one.designation}: least squares restarted from {one.start}")
    elif one.run is not None and len(one.run.context.measurements) > one.filter_rows > 0:
        say(f"{one.designation}: least squares from the filter's estimate after the first {one.filter_rows} "
            f"observations (the filter ran over those only)")
    if one.run is not None:
        one.seeding = _seeding(one, first)
    if one.result is not None:
        one.result = _with_messages(one.result, [seeding_text(one), _short_arc_text(one)])


def _seeding(one: ObjectFit, fallback_from: str) -> dict[str, Any]:
    """``one.seeding`` from the run's IOD cloud (method, rows, why)."""
    meta = dict(getattr(one.run.context.iod_cloud, "meta", None) or {})
    name = one.scenario.components["iod"].name
    rows = meta.get("seed_rows", meta.get("fit_indices", []))
    if name == RANGING_IOD:
        why = str(meta.get("why", ""))
        if fallback_from:
            why += f"; used because the template's IOD gave no fit: {fallback_from}"
        extension = list(meta.get("extension", []))
    else:
        rest = (f"the filter over the first {one.filter_rows} observations (the least squares over all "
                f"{len(one.run.context.measurements)})" if one.filter_rows else "the filter over the rest")
        why, extension = (f"the kinematic fit of the first {len(rows)} observations of the first pass (the "
                          f"template's IOD), then {rest}"), []
    return {"method": name, "rows": [int(i) for i in rows], "why": why, "extension": extension}


def seeding_text(one: ObjectFit) -> str:
    """One line: which observations seeded ``one``'s fit, by which method and why ("" for none)."""
    s = one.seeding
    if not s:
        return ""
    ms = one.run.context.measurements
    rows = s["rows"]
    where = ""
    if rows:
        utc = [units.format_utc(units.tu_to_utc(one.scenario.epoch, float(ms.times[i])))[:16] for i in (rows[0], rows[-1])]
        sites = sorted({ms.site_at(int(i)) for i in rows} - {""})
        where = f" on {len(rows)} observations from {utc[0]} to {utc[1]}Z" + (f" ({', '.join(sites)})" if sites else "")
    steps = f"; least squares extended in {len(s['extension'])} step(s)" if s.get("extension") else ""
    return f"seeded by the IOD '{s['method']}'{where}: {s['why']}{steps}"


def _short_arc_text(one: ObjectFit) -> str:
    """Why the orbit is poorly determined when the observations span less than
    :data:`SHORT_ARC_HOURS` ("" otherwise)."""
    ms = one.run.context.measurements if one.run is not None else None
    if ms is None or len(ms) == 0:
        return ""
    hours = units.tu_to_hours(float(ms.times[-1] - ms.times[0]))
    if hours >= SHORT_ARC_HOURS:
        return ""
    r = one.result
    sigma = float(np.sqrt(np.trace(r.covariance_km[:3, :3])))
    return (f"the observations span only {hours:.1f} h: the orbit is poorly determined (1-sigma position "
            f"{sigma:,.0f} km, mostly along the line of sight: the distance is barely constrained); observe on "
            "more nights before trusting predictions")


def _with_messages(result: FitResult, lines: list[str]) -> FitResult:
    """``result`` with the non-empty ``lines`` added to its messages."""
    from dataclasses import replace

    add = tuple(line for line in lines if line)
    return replace(result, messages=tuple(result.messages) + add) if add else result


def _lov_sigmas(one: ObjectFit, choices: FitChoices) -> float | None:
    """How far the fit's line of variations goes: ``choices.lov`` sigmas (0: none), or with "auto"
    None (until the data rule it out, :mod:`.lov_solutions`) when the fit is poorly determined, else 0."""
    if choices.lov is not None:
        return choices.lov
    det = one.determination
    return None if det is not None and not getattr(det, "well", True) else 0.0


def _follow_line(one: ObjectFit, job: "_Job") -> None:
    """``one.lov``: the converged fit's line of variations (:func:`_lov_sigmas`); with "auto", a
    better solution found along it replaces the fit (its findings and its line made again)."""
    from cistrack.fitting.fit_findings import add_findings
    from cistrack.fitting.lov_solutions import better_solution, follow_line

    sigmas = _lov_sigmas(one, job.choices) if one.ok else 0.0
    if sigmas == 0:
        return
    ctx, opts = one.run.context, job.choices.options
    job.say(f"{one.designation}: line of variations " + ("until the data rule it out" if sigmas is None
                                                         else f"to +-{sigmas:g} sigma"))
    with reported_to(job.log):
        one.lov = follow_line(ctx.dynamics, ctx.sensor, ctx.measurements, one.result, opts, sigmas)
        better = (better_solution(ctx.dynamics, ctx.sensor, ctx.measurements, one.result, one.lov, opts)
                  if sigmas is None and job.choices.prior == "none" and not getattr(one, "maneuvers", None) else None)
        if better is not None:
            job.say(f"{one.designation}: {better.messages[-1]}")
            one.result = better
            _refuse_unreportable(one)
            add_findings(one, job.registry, job.say)
            _note_rejected_epoch(one)
            one.lov = follow_line(ctx.dynamics, ctx.sensor, ctx.measurements, one.result, opts, None) if one.ok else []
    _horizon_along_line(one)


def _horizon_along_line(one: ObjectFit) -> None:
    """The determination made again with its horizon's orbits drawn along the line of variations
    when the line bends away from the covariance."""
    from cistrack.fitting.determination import determination
    from cistrack.least_squares.line_of_variations import line_summary

    if not one.ok or one.determination is None or len(one.lov) < 2 or line_summary(one.lov, one.result)["linear"]:
        return
    ctx = one.run.context
    dynamics = getattr(one, "dynamics", None) or ctx.dynamics
    one.determination = determination(one.result, dynamics, ctx.sensor, ctx.measurements, line=one.lov)


def fit_files(files: Iterable[str | Path], *, out: str | Path | None = None,
              settings: Iterable[str] | None = None, registry: Registry | None = None,
              log: Callable[[str], None] | None = None, progress: bool = False,
              overwrite: bool = False, words: OptionWords = CLI_WORDS) -> list[ObjectFit]:
    """Fit an orbit to each object observed in ``files`` (see the module docstring).

    Parameters
    ----------
    files : paths of observation files (any registered format; several files and sites merge)
    out : results directory (default ``runs/fit-<designation>``); with several objects, each
        gets ``OUT/fit-<designation>``
    settings : ``TABLE.KEY=VALUE`` items as ``--set`` takes them: scenario tables of the template,
        ``measurements.reader.KEY`` (reader parameters, e.g. ``sigma_arcsec``) and ``fit.KEY``
        (:func:`fit_choices`)
    log : receives one line per stage; ``progress``: progress on stderr, the filter's progress bar
        and, without ``log``, the stage lines (:func:`cistrack.runs.progress.stage_log`)
    overwrite : replace a ``cistrack run``'s results or another object's fit in a directory
        (refused otherwise: :func:`cistrack.fitting.fit_replacing.check_fit_replacing`); an earlier
        fit of the same object is always redone
    words : the caller's options, as refusals and notes name them (``--out``, ``--overwrite`` by
        default; :data:`cistrack.results.earlier_run.PYTHON_WORDS` for :func:`cistrack.fit`)

    Returns one :class:`ObjectFit` per object, in order of first appearance. Errors in the input
    (files, settings, output directory) raise before any run; a run or fit that fails is reported
    in its ObjectFit (``failure``, ``result.converged``).
    """
    reg = registry or default_registry()
    log, long_names = _clipping(log, progress)
    say = log or (lambda m: None)
    scen_settings, fit_table, reader_params = _split_settings(settings)
    choices = fit_choices(fit_table)
    job = _Job(scen_settings, choices, reg, progress, log)
    objects, aside = _modelled_objects(_read_named(list(files), reg, reader_params, say, long_names), job)
    plans, top_stale = _plans(objects, out, overwrite, words)
    where = words.out.rstrip("=") if out is not None else "the results directory"
    stale_of: dict[Path, list[Path]] = {}  # what an earlier fit of the other fit.arcs form left (--overwrite)
    for obs, d in plans:  # validate every directory before the first run (the scenarios were: _modelled_arcs)
        replaced = check_fit_replacing(d, obs.designation, where, overwrite, words,
                                       (READ_EPOCH, obs.measurements.times))
        if replaced:
            say(f"{words.overwrite}: replacing {replaced} in {d}")
        stale_of[d] = check_fit_form(d, choices.arcs.arcs == "each", where, overwrite, words)
    if top_stale:
        remove_other_form(Path(out), top_stale)
        say(f"{words.overwrite}: removed the earlier fit of one object in {out} ({FIT_RECORD} and its files)")
    results = []
    for obs, d in plans:
        stale = stale_of[d]
        if stale:
            remove_other_form(d, stale)
            say(f"{words.overwrite}: removed the earlier fit of another fit.arcs in {d} "
                f"({', '.join(p.name for p in stale)})")
        check_output_dir(d, where, records=(MANIFEST, FIT_RECORD))
        with fit_lock(d, where), copies_read_quietly(), library_thread_limit(blas=1):  # one fit at a time
            # in a directory; what it replaces checked again under it; the reader's warnings were given
            # for the user's files; one BLAS thread for the least squares' small matrices, as in a run
            check_fit_replacing(d, obs.designation, where, overwrite, words, (READ_EPOCH, obs.measurements.times))
            results += _fit_arcs(obs, d, job, aside[obs.designation])
    return results


def _plans(objects: list[ObjectObservations], out: str | Path | None, overwrite: bool,
           words: OptionWords) -> tuple[list[tuple[ObjectObservations, Path]], list[Path]]:
    """(each object with its results directory: ``out``, or with several objects ``out/fit-<designation>``,
    default ``runs/fit-<designation>``), and the top-level fit of one object in ``out`` that a fit of
    several objects removes with ``overwrite`` (refused without: :func:`check_several_objects_dir`)."""
    plans = []
    for obs, slug in zip(objects, _directory_names([o.designation for o in objects])):
        d = Path(out) if out is not None and len(objects) == 1 else (Path(out) / slug if out is not None
                                                                       else Path("runs") / slug)
        plans.append((obs, d))
    if out is None or len(objects) == 1:
        return plans, []
    return plans, check_several_objects_dir(out, words.out.rstrip("="), overwrite, words)


def _clipping(log: Callable[[str], None] | None, progress: bool) -> tuple[Callable[[str], None] | None, list[str]]:
    """(the ``log`` a fit says its stages to, the designations too long to show whole): ``log`` (or,
    with ``progress`` and no ``log``, the stage lines on stderr) with each of those designations cut
    in every line (:func:`cistrack.errors.clipped`; the list is filled once the files are read:
    :func:`_read_named`). A 100,000-character trkSub had been echoed whole in each line (probe L10)."""
    if progress and log is None:
        from cistrack.runs.progress import stage_log
        log = stage_log()
    names: list[str] = []
    if log is None:
        return None, names
    shown = log

    def say(message: str) -> None:
        for name in names:
            message = message.replace(name, clipped(name))
        shown(message)
    return say, names


def _read_named(files: list, registry: Registry, reader_params: dict[str, Any], say: Callable[[str], None],
                long_names: list[str]) -> list[ObjectObservations]:
    """:func:`read_object_observations` of ``files``, adding to ``long_names`` the designations a
    message cuts (:func:`_clipping`)."""
    read = read_object_observations(files, registry, reader_params, say)
    long_names += [o.designation for o in read if clipped(o.designation) != o.designation]
    return read


@dataclass(frozen=True)
class _Job:
    """What every object's fit shares: scenario settings, fit choices, registry, progress, log."""

    settings: dict
    choices: FitChoices
    registry: Registry
    progress: bool
    log: Callable[[str], None] | None

    def say(self, message: str) -> None:
        if self.log is not None:
            self.log(message)


def _last_observation(obs: ObjectObservations) -> ObjectObservations:
    """``obs`` with its last observation only: a scenario started there checks that the arc's end
    lies inside the years the dynamics and sensor model (an arc from 2026 to a row dated 2060 had
    been fitted over 34 years, past DE421's 2052)."""
    keep = np.zeros(len(obs.measurements.times), dtype=bool)
    keep[int(np.argmax(obs.measurements.times))] = True
    return replace(obs, measurements=obs.measurements.subset(keep))


def _outside_arc(part: ObjectObservations, obs_file: Path, job: _Job) -> str:
    """Why the fit cannot model the arc ``part`` (its start or end outside the years of the dynamics
    or the sensor, e.g. DE421's), in words; "" when it can."""
    try:
        _scenario(part, obs_file, job.settings, job.registry)
        _scenario(_last_observation(part), obs_file, job.settings, job.registry)
    except ConfigError as exc:
        if "'epoch'" not in str(exc):
            raise
        found = re.search(r"(\w+ '[^']+'): parameter 'epoch' = '[^']*' is invalid: (.*)$", str(exc), re.S)
        return f"{found[1]}: the epoch {found[2]}" if found else str(exc)
    return ""


def _modelled_arcs(obs: ObjectObservations, job: _Job) -> tuple[ObjectObservations, str]:
    """(``obs`` without the long-gap arcs the fit cannot model (:func:`_outside_arc`) and does not fit,
    a note saying which and why, "" for none). Only the arc that is fitted (``fit.arcs``: the latest
    that determines an orbit, every arc, or all of them) is refused when it lies outside
    (:func:`_checked_scenario`): one observation with a mistyped year 1899 had refused the whole
    file, while the same typo dated 1901 was set aside as an earlier arc (probe I4).
    The scenarios are checked only, before any run: their observation file is not written yet."""
    from cistrack.fitting.fit_findings import arcs_to_fit, latest_determined_arc

    arcs, choices, obs_file = job.choices.arcs, job.choices, Path("observations.psv")
    if arcs.arcs == "all":
        _checked_scenario(obs, obs_file, job.settings, job.registry, choices)
        return obs, ""
    parts = arcs_to_fit(obs, "each", arcs.arc_gap_days)
    fitted = latest_determined_arc(obs, arcs.arc_gap_days)[1] if arcs.arcs == "latest" else None
    end = float(fitted.measurements.times[0]) if fitted is not None else math.inf
    why = {i: _outside_arc(p, obs_file, job) for i, p in enumerate(parts) if float(p.measurements.times[0]) < end}
    out = [i for i, w in why.items() if w]
    if len(out) == len(parts):
        _checked_scenario(obs, obs_file, job.settings, job.registry, choices)
    times = np.asarray(obs.measurements.times, dtype=float)
    keep = ~np.isin(times, np.concatenate([parts[i].measurements.times for i in out])) if out else times == times
    kept = replace(obs, measurements=obs.measurements.subset(keep))
    _checked_scenario(fitted or kept, obs_file, job.settings, job.registry, choices)
    if not out:
        return kept, ""
    first = parts[out[0]].measurements
    when = units.tu_to_utc(units.parse_utc(READ_EPOCH), float(first.times[0]))
    note = (f"{int((~keep).sum())} observation(s) in {len(out)} arc(s) more than {arcs.arc_gap_days:g} days from the "
            f"others (the first from site {first.site_at(0)} on {when:%Y-%m-%d}) are not fitted: outside the years "
            f"the fit can model ({why[out[0]]})")
    job.say(f"{obs.designation}: {note}")
    return kept, note


def _modelled_objects(objects: list[ObjectObservations], job: _Job) -> tuple[list[ObjectObservations], dict[str, str]]:
    """(each object's observations the fit can model, the note on those set aside by designation):
    :func:`_modelled_arcs` of each."""
    modelled = [_modelled_arcs(o, job) for o in objects]
    return [o for o, _ in modelled], {o.designation: note for o, note in modelled}


def _fit_arcs(obs: ObjectObservations, d: Path, job: _Job, aside: str = "") -> list[ObjectFit]:
    """The fits of one object: its latest arc (default), each arc in ``d/arc-<first date>``, or all
    of it at once (``fit.arcs``); each written to its directory. ``aside``: a note on the arcs set
    aside (:func:`_modelled_arcs`), which every fit's messages give."""
    from cistrack.fitting.fit_findings import arcs_to_fit

    arcs = job.choices.arcs
    if arcs.arcs == "latest":
        return [_fit_latest_determined(obs, d, job, aside)]
    sets = arcs_to_fit(obs, arcs.arcs, arcs.arc_gap_days)
    if arcs.arcs == "all":
        return [_finish(_fit_latest(obs, sets[0], d, job), sets[0], job)]
    out = []
    for part in sets:
        first = units.tu_to_utc(units.parse_utc(READ_EPOCH), float(part.measurements.times[0]))
        sub = d / f"arc-{first:%Y-%m-%d}"
        check_output_dir(sub, "the arc's results directory", records=(MANIFEST, FIT_RECORD))
        out.append(_finish(_noted(_fit_run(part, sub, job), aside), part, job))
    return out


def _noted(one: ObjectFit, note: str) -> ObjectFit:
    """``one`` with ``note`` in its fit's messages, or in its failure when there is no fit."""
    if note and one.result is not None:
        one.result = _with_messages(one.result, [note])
    elif note:
        one.failure = f"{one.failure}; {note}" if one.failure else note
    return one


def _fit_latest_determined(obs: ObjectObservations, d: Path, job: _Job, aside: str = "") -> ObjectFit:
    """The fit of the latest arc that determines an orbit (lone tracklets after it are left out,
    and the fit says so: :func:`cistrack.fitting.fit_findings.latest_determined_arc`); ``aside``:
    a note on the earlier arcs set aside, given with it."""
    from cistrack.fitting.fit_findings import earlier_arcs_text, latest_determined_arc

    upto, arc, note = latest_determined_arc(obs, job.choices.arcs.arc_gap_days)
    if note:
        job.say(f"{obs.designation}: {note}")
    one = _fit_latest(upto, arc, d, job)
    if _no_start(one):
        fallback = _earlier_fittable(obs, arc, one.failure, d, job)
        if fallback is not None:
            one, arc, note = fallback
        else:
            one = _fit_latest(upto, arc, d, job) if _tried_earlier(obs, arc, job) else one
            note = "; ".join(n for n in (note, earlier_arcs_text(obs, arc, job.choices.arcs.arc_gap_days)) if n)
    return _finish(_noted(one, "; ".join(n for n in (aside, note) if n)), arc, job)


_NO_START = "the filter run failed before its first step"


def _no_start(one: ObjectFit) -> bool:
    """Whether ``one`` failed before its filter's first step (no IOD started from its observations;
    not a lone tracklet, which says so itself)."""
    return one.run is None and one.result is None and not one.undetermined and one.failure.startswith(_NO_START)


def _earlier_candidate(obs: ObjectObservations, failed: ObjectObservations, job: _Job):
    """(the observations up to it, the latest arc before ``failed`` that is more than a lone
    tracklet), or None when there is none."""
    from cistrack.fitting.determination import is_lone_tracklet
    from cistrack.fitting.fit_findings import before_arc, latest_determined_arc

    before = before_arc(obs, failed)
    if before is None:
        return None
    upto, arc, _ = latest_determined_arc(before, job.choices.arcs.arc_gap_days)
    return None if is_lone_tracklet(arc.measurements) else (upto, arc)


def _tried_earlier(obs: ObjectObservations, arc: ObjectObservations, job: _Job) -> bool:
    """Whether :func:`_earlier_fittable` fitted an earlier arc into the directory (its files are
    then replaced by the latest arc's again)."""
    return _earlier_candidate(obs, arc, job) is not None


def _earlier_fittable(obs: ObjectObservations, arc: ObjectObservations, why: str, d: Path,
                      job: _Job) -> tuple[ObjectFit, ObjectObservations, str] | None:
    """When the fit of the latest arc ``arc`` failed before its first step (``why``; e.g. two pairs
    of observations days apart, from which no IOD starts): (the fit of the latest earlier arc that
    starts, that arc, the note naming what is left out after it), trying the arcs latest first; None
    when none does. A stray pair filed under an object's designation had made the fit fail on it
    alone, its 23 earlier observations unmentioned (probe N2)."""
    from cistrack.fitting.fit_findings import first_clause, left_out_note

    failed = arc
    while (candidate := _earlier_candidate(obs, failed, job)) is not None:
        upto, earlier = candidate
        job.say(f"{obs.designation}: the arc from {_day(failed)} cannot be fitted ({first_clause(why)}); fitting "
                f"the arc before it, from {_day(earlier)}")
        one = _fit_latest(upto, earlier, d, job)
        if not _no_start(one):
            end = float(earlier.measurements.times[-1])
            left = replace(obs, measurements=obs.measurements.subset(np.asarray(obs.measurements.times) > end))
            return one, earlier, left_out_note(left, earlier, why)
        failed = earlier
    return None


def _day(part: ObjectObservations) -> str:
    """The UTC date of ``part``'s first observation, YYYY-MM-DD."""
    return f"{units.tu_to_utc(units.parse_utc(READ_EPOCH), float(part.measurements.times[0])):%Y-%m-%d}"


def _fit_run(obs: ObjectObservations, d: Path, job: _Job) -> ObjectFit:
    """The IOD, filter and least squares of ``obs`` into the directory ``d``."""
    suffix = write_merged(d / "observations", obs.measurements, obs.designation, job.registry)
    scen = _scenario(obs, d / f"observations{suffix}", job.settings, job.registry)
    job.say(f"{obs.designation}: {len(obs.measurements)} observations; filter '{scen.components['filter'].name}' "
            f"after IOD '{scen.components['iod'].name}', epoch {units.format_utc(scen.epoch)[:19]}Z, "
            f"{scen.duration_days:g} days; results -> {d}")
    one = ObjectFit(obs.designation, d, scen, notes=list(obs.notes), choices=job.choices)
    if not _lone_tracklet(one, obs, job):
        early = _early_scenario(obs, scen, d, job)
        _fit_object(one, job.registry, job.progress, job.say if job.log else None, early)
        if not one.searched:
            add_maneuvers(one, job.say)
    return one


def _lone_tracklet(one: ObjectFit, obs: ObjectObservations, job: _Job) -> bool:
    """When ``obs`` are one lone tracklet (:func:`cistrack.fitting.determination.is_lone_tracklet`):
    ``one.undetermined`` and ``one.failure`` say that it determines no orbit, and what it gives
    (its sky motion; the admissible region of the ranging IOD :data:`RANGING_IOD`, with the
    scenario's own ranging settings when its IOD is that one); nothing runs. False otherwise."""
    from cistrack.astro.site_network import build_site_network
    from cistrack.fitting.arcs import in_time_base
    from cistrack.fitting.determination import is_lone_tracklet, lone_tracklet_report

    if not is_lone_tracklet(obs.measurements):
        return False
    scen = one.scenario
    ms = in_time_base(obs.measurements, units.parse_utc(READ_EPOCH), scen.epoch)
    try:
        ranging = scen if scen.components["iod"].name == RANGING_IOD else _ranging_scenario(scen, job.registry)
        sensor = build_site_network(scen.components["sensor"], job.registry, ms)
        cloud = ranging.build("iod", job.registry).estimate(ms, sensor, np.random.default_rng(0))
        region = dict(cloud.meta.get("admissible_region", {}))
        curve = (cloud.meta.get("tracklets") or [{}])[0]
    except CistrackError as exc:
        region, curve = {"why_none": f"no admissible region: {exc}"}, {}
    one.undetermined = lone_tracklet_report(ms, region, scen.epoch, curve)
    one.failure = one.undetermined["sentence"]
    job.say(f"{one.designation}: {one.failure}")
    return True


def _fit_latest(obs: ObjectObservations, latest: ObjectObservations, d: Path, job: _Job) -> ObjectFit:
    """The fit of the latest arc; when its earlier groups do not link to its latest ones, the fit
    again of those that do (:mod:`.fit_findings`), with the residual ladder of the rest."""
    from cistrack.fitting.fit_findings import arc_report, kept_observations

    one = _fit_run(latest, d, job)
    if job.choices.arcs.arcs != "latest":
        return one
    report = arc_report(one, obs, job.choices.arcs, job.registry)
    if report is None:
        return one
    if len(report.rows) < len(latest.measurements):
        job.say(f"{obs.designation}: {report.notes[-1]}; fitting again without them")
        one = _fit_run(kept_observations(obs, report), d, job)
        if not one.ok:
            return one
    one.arcs = report
    if report.notes:
        one.result = _with_messages(one.result, list(report.notes))
    return one


def _note_rejected_epoch(one: ObjectFit) -> None:
    """A message when the fit's epoch lies more than a day after the last observation it used (the
    observations there were rejected): the state and covariance there are the orbit's, propagated."""
    r = one.result
    if r is None or r.residuals is None or len(r.residuals.times) == 0:
        return
    used = np.asarray(r.residuals.times, dtype=float)[~np.asarray(r.residuals.rejected, dtype=bool)]
    if used.size == 0:
        return
    gap_days = float(units.tu_to_days(float(r.epoch) - float(np.max(used))))
    if gap_days > 1.0:
        one.result = _with_messages(r, [f"the fit epoch is {gap_days:.1f} days after the last observation it used "
                                        "(the later ones were rejected); the state there is the fitted orbit propagated"])


CISLUNAR_LIMIT_KM = MAX_DISTANCE_KM
"""A converged fit whose state lies farther than this from the Earth (about eight lunar distances,
the ranging IOD's ``range_max_km``) is not a cislunar orbit: the observations left the distance
free (a star, or a body far beyond the Moon, barely moves against the stars), and the fit is not
reported as converged."""


def _refuse_not_cislunar(one: ObjectFit) -> None:
    """``one.result`` not converged, saying why, when its state lies beyond :data:`CISLUNAR_LIMIT_KM`."""
    from cistrack.astro.primaries import MU_EARTH_MOON

    r = one.result
    if r is None or not r.converged:
        return
    x = np.asarray(r.state_km, dtype=float)
    earth_km = np.array([-MU_EARTH_MOON * units.LU_KM, 0.0, 0.0])
    distance = float(np.linalg.norm(x[:3] - earth_km))
    if distance <= CISLUNAR_LIMIT_KM:
        return
    speed = float(np.linalg.norm(x[3:]))
    one.result = replace(r, converged=False, messages=tuple(r.messages) + (
        f"not a cislunar orbit: the fitted state lies {distance:.3g} km from the Earth (beyond "
        f"{CISLUNAR_LIMIT_KM:.0e} km), moving {speed:.3g} km/s in the rotating frame; the observations "
        "do not determine the distance (an object that barely moves against the stars: a star, a "
        "distant body, or observations of different objects?)",))


def _refuse_unconfined(one: ObjectFit) -> None:
    """``one.result`` not converged, saying why, when its 1-sigma position (km) or velocity (km/s),
    scaled by the noise scale where above 1, exceeds :data:`MAX_DISTANCE_KM` or :data:`MAX_SPEED_KMS`:
    the observations' stated uncertainties are too large to confine the orbit to cislunar space, and
    ``cistrack export`` and ``predict`` read no converged fit with such a covariance."""
    r = one.result
    if r is None or not r.converged:
        return
    sig = np.asarray(r.sigmas_km, dtype=float) * sigma_factor(r.noise_scale)
    pos, vel = float(np.max(sig[:3])), float(np.max(sig[3:]))
    if pos <= MAX_DISTANCE_KM and vel <= MAX_SPEED_KMS:
        return
    one.result = replace(r, converged=False, messages=tuple(r.messages) + (
        f"not a determined orbit: its 1-sigma position is {pos:.3g} km and velocity {vel:.3g} km/s (a fit "
        f"is reported only within {MAX_DISTANCE_KM:.0e} km and {MAX_SPEED_KMS:g} km/s); the observations' "
        "stated uncertainties (ADES rmsRA/rmsDec, or the reader's sigma_arcsec) are too large to confine it",))


def _refuse_unreportable(one: ObjectFit) -> None:
    """The checks every fit reported passes, the first and one found along its line of variations
    alike: an orbit within cislunar space (:func:`_refuse_not_cislunar`) that its observations
    confine (:func:`_refuse_unconfined`)."""
    _refuse_not_cislunar(one)
    _refuse_unconfined(one)


def _name_failure(one: ObjectFit) -> None:
    """``one.failure``, when empty, says why a fit made is not reported as converged
    (:func:`cistrack.fitting.fit_record.unsound_reason`): a FAILED fit had carried ``failure`` ""
    and the one-line reason "converged after 14 iterations" (probe L6)."""
    from cistrack.fitting.fit_record import unsound_reason

    from cistrack.fitting.stated_noise import too_small_words

    if one.result is not None and not one.result.converged and not one.failure:
        one.failure = unsound_reason(one.result.messages)
    words = too_small_words(one.result.residuals) if one.result is not None and one.failure else ""
    if words:  # said first: the failure's verdict (a maneuver's) is drawn with weights that tight (probe N1)
        one.failure = f"{words}; {one.failure}"


def _finish(one: ObjectFit, obs: ObjectObservations, job: _Job) -> ObjectFit:
    """Determination, events and the line of variations of a converged fit; the results files."""
    from cistrack.fitting.fit_findings import add_findings
    from cistrack.fitting.fit_record import outputs_text, write_fit_outputs

    _refuse_unreportable(one)
    add_findings(one, job.registry, job.say)
    _note_rejected_epoch(one)
    _follow_line(one, job)
    _name_failure(one)
    job.say(f"{obs.designation}: writing {outputs_text(one)} to {one.directory}")
    write_fit_outputs(one, obs)
    return one
