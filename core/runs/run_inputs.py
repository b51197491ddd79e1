"""What a run reads or plans before its first filter step, checked against the scenario.

- :func:`read_scenario_observations`: the scenario's observation file through a registered
  reader; refused when it is a directory or of no known format, when observations lie outside
  the scenario's span (epoch to epoch + duration_days), or when it has more observation times
  than a run may take as filter steps.
- :func:`plan_measurement_times`: the schedule's times, with its refusals (too many times to
  plan) named as the scenario's ``[schedule]`` table.
- :func:`estimate_iod`: the IOD, whose failure on measurements simulated from a ``state_km``
  truth points at that state, and whose own exception or wrong result (not a ParticleCloud, or
  one dated outside the measurements it was given) names it.
- :func:`simulate_measurements`: the sensor's simulated measurements, its refusals naming the sensor.

Every refusal is a :class:`~cistrack.errors.CistrackError` naming the scenario file and key.
"""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Callable

import numpy as np

from cistrack import units
from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.errors import (CistrackError, ConfigError, IODError, MeasurementError, ParameterError, PluginError,
                             exception_text)
from cistrack.interfaces.component import component_name
from cistrack.interfaces.schedule import checked_plan
from cistrack.interrupts import plugin_fault
from cistrack.model.belief import ParticleCloud
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry
from cistrack.scenario.loading import Scenario
from cistrack.scenario.work_limits import check_steps

__all__ = ["read_scenario_observations", "weights_note", "reading_own_copies", "check_observation_span", "plan_measurement_times", "estimate_iod",
           "checked_iod_cloud", "in_table", "simulate_measurements"]

_SPAN_TOLERANCE_TU = 1e-9
"""Observations this close to the span's ends (about 0.4 ms) count as inside."""


def read_scenario_observations(scenario: Scenario, sensor: Any, registry: Registry,
                               say: Callable[[str], None]) -> tuple[MeasurementSet, Any]:
    """The observations of ``scenario``'s ``[measurements] file`` and the sensor that took them
    (the scenario's sensor placed at each site, for files from several observatories)."""
    from cistrack.runs.observation_files import read_checked, reader_for

    path = scenario.measurements_file
    say(f"reading measurements from {path}")
    spec = scenario.measurements_reader
    try:
        reader = spec.build(registry) if spec is not None else reader_for(path, registry=registry)
    except MeasurementError as exc:
        raise ConfigError(f"{scenario.source}: [measurements]: key 'file': {exc}") from None
    measurements = read_checked(reader, path, scenario.epoch, registry)
    if weights_note(measurements) and not _OWN_COPIES.get():
        say(weights_note(measurements))
    check_observation_span(scenario, measurements)
    groups = measurements.time_groups()
    check_steps(len(groups), f"{scenario.source}: [measurements]: key 'file' = {str(path)!r}",
                f"{len(measurements):,} observations at {len(groups):,} times")
    if measurements.sites is not None:  # several observatories: the sensor placed at each
        from cistrack.astro.site_network import build_site_network
        sensor = build_site_network(scenario.components["sensor"], registry, measurements)
        say(f"{len(measurements)} measurements from sites {', '.join(measurements.site_keys())}")
    return measurements, sensor


_OWN_COPIES: ContextVar[bool] = ContextVar("cistrack_own_copies", default=False)


@contextmanager
def reading_own_copies() -> Iterator[None]:
    """Within it, reading a scenario's observations says nothing of their weights: the file is a
    copy cistrack wrote (``cistrack fit``'s ``observations-early.psv``), its uncertainties those the
    user's files had or the reader's default filled in, and the weights were told of the user's
    files when they were read (a file without uncertainties had been said to have its own)."""
    token = _OWN_COPIES.set(True)
    try:
        yield
    finally:
        _OWN_COPIES.reset(token)


def weights_note(measurements: MeasurementSet) -> str:
    """One line on where the observations' weights came from: the file's own uncertainties, or
    for how many the reader's default ``sigma_arcsec`` (meta ``default_sigma_count`` and
    ``default_sigma_arcsec``, which the astrometry readers record); "" for a reader that does
    not record them."""
    meta = measurements.meta
    n, fmt = meta.get("default_sigma_count"), meta.get("format", "the")
    if n is None:  # a reader that does not record it
        return ""
    if n == 0:
        return f"weights: the file's own uncertainties for all {len(measurements)} observations"
    partial, sigma = int(meta.get("default_sigma_partial", 0)), meta.get("default_sigma_arcsec")
    if meta.get("sigma_from_file") is False:
        return (f"weights: the {fmt} reader's sigma_arcsec = {sigma:g} arcsec on the sky for all {n} observations "
                "(sigma_from_file = false: the file's own uncertainties are not used)")
    default = (f"the {fmt} reader's default sigma_arcsec = {sigma:g} arcsec on the sky (RA x cos(Dec), Dec) "
               "applies")
    if partial == n:
        return (f"weights: {n} of {len(measurements)} observations state the uncertainty of one angle only: "
                f"the file's is used for it, and for the other {default}; set [measurements] "
                "reader.sigma_arcsec to your data's noise")
    half = f" ({partial} of them state one angle's and take the default for the other)" if partial else ""
    return (f"weights: {n} of {len(measurements)} observations have no uncertainty in the file{half}: "
            f"{default}; set [measurements] reader.sigma_arcsec to your data's noise")


def _utc(scenario: Scenario, t: float) -> str:
    return units.format_utc(units.tu_to_utc(scenario.epoch, t))[:19] + "Z"


def check_observation_span(scenario: Scenario, measurements: MeasurementSet) -> None:
    """Refuse observations before the scenario's epoch or after epoch + duration_days, naming
    the file, how many lie outside, the first and last of them and the span."""
    t = np.asarray(measurements.times, dtype=float)
    end = scenario.duration
    outside = (t < -_SPAN_TOLERANCE_TU) | (t > end + _SPAN_TOLERANCE_TU)
    if not np.any(outside):
        return
    bad = t[outside]
    days = units.tu_to_days(bad)
    where = (f"{bad.size:,} of {t.size:,} observations lie outside the scenario's span "
             f"({_utc(scenario, 0.0)} to {_utc(scenario, end)}: top-level 'epoch' + 'duration_days' = "
             f"{scenario.duration_days:g})")
    first, last = float(bad.min()), float(bad.max())
    shown = (f"from {_utc(scenario, first)} ({float(days.min()):,.1f} days from the epoch) to "
             f"{_utc(scenario, last)} ({float(days.max()):,.1f} days)" if bad.size > 1
             else f"at {_utc(scenario, first)} ({float(days.min()):,.1f} days from the epoch)")
    raise ConfigError(f"{scenario.source}: [measurements]: key 'file' = {str(scenario.measurements_file)!r}: "
                      f"{where}, {shown}; set 'epoch' and 'duration_days' to cover the observations, or "
                      "remove those outside from the file")


def plan_measurement_times(scenario: Scenario, schedule: Any, passes: list, rng: np.random.Generator) -> np.ndarray:
    """The schedule's measurement times (TU); a schedule refusing its parameters for these
    passes (e.g. too many times) is named as the scenario's ``[schedule]`` table."""
    try:
        planned = schedule.plan(passes, scenario.duration, rng)
    except ParameterError as exc:
        raise ConfigError(f"{scenario.source}: [schedule]: {exc}") from None
    except (CistrackError, MemoryError):
        raise
    except BaseException as exc:  # the plugin's own bug (a KeyboardInterrupt no signal raised too): named
        if not plugin_fault(exc):
            raise
        raise PluginError(f"{scenario.source}: [schedule] '{component_name(schedule)}': plan() raised "
                          f"{exception_text(exc)}") from exc
    return checked_plan(planned, passes, scenario.duration,
                        f"{scenario.source}: [schedule] '{component_name(schedule)}': plan()")




def estimate_iod(scenario: Scenario, iod: Any, measurements: MeasurementSet, sensor: Any,
                 rng: np.random.Generator, simulated: bool, registry: Registry | None = None) -> ParticleCloud:
    """The IOD's cloud. When the measurements were simulated from a ``[truth] state_km`` and the
    IOD finds no orbit, the message points at that state (where the target is from Earth). An IOD
    that raises its own exception (not an IODError), or returns anything but a ParticleCloud at
    the time of one of ``measurements``, is an IODError naming it (and its distribution, from
    ``registry``)."""
    who = registry.describe("iod", component_name(iod)) if registry is not None else f"iod '{component_name(iod)}'"
    try:
        cloud = iod.estimate(measurements, sensor, rng)
    except IODError as exc:
        if not simulated or scenario.truth_state is None:
            raise
        earth = np.array([-MU_EARTH_MOON, 0.0, 0.0])  # the Earth in the synodic frame (LU)
        r_km = float(np.linalg.norm(scenario.truth_state[:3] - earth) * units.LU_KM)
        where = f" (it puts the target {r_km:,.0f} km from Earth at t = 0)"
        raise IODError(f"{exc} The measurements were simulated from {scenario.source}: [truth]: key "
                       f"'state_km'{where}: check that state, which the IOD's bounds must admit.") from None
    except (CistrackError, MemoryError):
        raise
    except BaseException as exc:  # the plugin's own bug (GeneratorExit, a KeyboardInterrupt no signal raised): named
        if not plugin_fault(exc):
            raise
        raise IODError(f"{who}: estimate() raised {exception_text(exc)}") from exc
    return checked_iod_cloud(cloud, measurements, who)


def checked_iod_cloud(cloud: Any, measurements: MeasurementSet, who: str) -> ParticleCloud:
    """``cloud``, what the IOD ``who`` returned for ``measurements``, unless it is not a
    ParticleCloud or its epoch (TU) lies outside the measurements' times (to 1e-9 TU relative): an
    IOD's cloud is at the epoch of the last measurement it used, so inside the run. IODError
    naming ``who`` otherwise."""
    if not isinstance(cloud, ParticleCloud):
        raise IODError(f"{who}: estimate() returned {type(cloud).__name__}, not a ParticleCloud (cistrack.api."
                       "ParticleCloud: (N, 6) states at the epoch of the last measurement it used)")
    _check_cloud_states(cloud, who)
    times = np.asarray(measurements.times, dtype=float)
    if times.size == 0:
        return cloud
    first, last, t = float(times.min()), float(times.max()), float(cloud.epoch)
    slack = 1e-9 * max(1.0, abs(first), abs(last))
    if not first - slack <= t <= last + slack:
        raise IODError(f"{who}: estimate() returned a cloud at t = {units.tu_to_days(t):,.3f} d, outside the "
                       f"{times.size} measurements it was given ({units.tu_to_days(first):.3f} d to "
                       f"{units.tu_to_days(last):.3f} d); an IOD's cloud is at the epoch of the last measurement "
                       "it used")
    return cloud


def _check_cloud_states(cloud: ParticleCloud, who: str) -> None:
    """IODError naming ``who`` unless the cloud holds at least two states of 6 components, all finite:
    the filter would otherwise be blamed for the IOD's cloud (a cloud of 1 particle had been
    "filter 'pgm': the initial cloud has 1 particle": probe I8)."""
    n, d = cloud.states.shape
    if d != 6 or n == 0:
        raise IODError(f"{who}: estimate() returned a cloud with states of shape {cloud.states.shape}; a ParticleCloud "
                       "holds (N, 6) synodic states, N >= 2")
    if n == 1:
        raise IODError(f"{who}: estimate() returned a cloud of 1 particle; a filter starts from a spread of states "
                       "(N >= 2: the orbits the measurements allow)")
    bad = int(np.sum(~np.all(np.isfinite(cloud.states), axis=1)))
    if bad:
        raise IODError(f"{who}: estimate() returned a cloud whose states are not all finite ({bad} of {n} hold NaN or inf)")


@contextmanager
def in_table(scenario: Scenario, where: str) -> Iterator[None]:
    """Within it, a ConfigError or MeasurementError whose message does not name the scenario file
    (a sensor's own: "sensor 'space-telescope': the observer's orbit hits Earth ...") is raised again
    naming the file and ``where``, the table it comes from (``[sensors.dro2]``, or with the file
    already: a component spec's ``where``)."""
    source = str(scenario.source)
    try:
        yield
    except (ConfigError, MeasurementError) as exc:
        if str(exc).startswith(source):
            raise
        raise type(exc)(f"{where if where.startswith(source) else f'{source}: {where}'}: {exc}") from None


def simulate_measurements(sensor: Any, states: np.ndarray, times: np.ndarray, rng: np.random.Generator,
                          registry: Registry) -> MeasurementSet:
    """``sensor.simulate(states, times, rng)``; a MeasurementError it gives (NaN values, sigmas that
    are not > 0, ...) names the sensor by its registered name and distribution, unless it does so itself."""
    try:
        return sensor.simulate(states, times, rng)
    except MeasurementError as exc:
        name = component_name(sensor)
        if str(exc).startswith(f"sensor '{name}'"):
            raise
        raise MeasurementError(f"{registry.describe('sensor', name)}: simulate() gave {exc}") from None
