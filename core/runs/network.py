"""Simulated measurements of a network of observers (``[sensors.<key>]`` tables): each observer
finds its own passes of the truth, plans its times with the scenario's schedule and measures; the
sets are merged into one time-ordered set naming each measurement's observer, answered for by a
:class:`~cistrack.astro.site_network.SiteNetwork` exactly as files from several observatories
are (the filters take measurements at one time in one step).

Random streams: the run's schedule and noise streams are each split into one child per observer
(in the order of the tables), so an observer's measurements do not change when another is added
after it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.astro.site_network import SiteNetwork, merge_sites
from cistrack.errors import ConfigError
from cistrack.interfaces import Pass
from cistrack.model.measurement import MeasurementSet
from cistrack.runs.run_inputs import in_table, plan_measurement_times, simulate_measurements

__all__ = ["NetworkObservations", "simulate_network", "skip_pass_in_progress", "iod_input"]


@dataclass
class NetworkObservations:
    """What a network saw: the merged measurements, the network sensor answering for them, every
    observer's passes (time-ordered) and each observer's passes by key."""

    measurements: MeasurementSet
    sensor: SiteNetwork
    passes: list[Pass]
    passes_by_observer: dict[str, list[Pass]]


def skip_pass_in_progress(passes: list, t0: float, say=lambda msg: None, who: str = "") -> list:
    """``passes`` without one already under way at ``t0``: the target is acquired at a rise."""
    if passes and passes[0].start <= t0 + 1e-12:
        say(f"skipping the pass in progress at t = 0{who}")
        return passes[1:]
    return passes


def simulate_network(scenario, registry, truth, grid: np.ndarray, grid_states: np.ndarray,
                     rngs: dict, say=lambda msg: None) -> NetworkObservations:
    """Measurements of ``truth`` (a :class:`~cistrack.runs.truth.Truth`) by every observer of
    ``scenario.observers``; ``rngs`` holds the run's "schedule" and "measurements" generators."""
    keys = list(scenario.observers)
    sched_rngs = rngs["schedule"].spawn(len(keys))
    noise_rngs = rngs["measurements"].spawn(len(keys))
    members, parts, by_key = {}, [], {}
    for key, s_rng, n_rng in zip(keys, sched_rngs, noise_rngs):
        with in_table(scenario, scenario.observers[key].where):  # which of several alike observers failed
            sensor = scenario.observers[key].build(registry)
            members[key] = sensor
            passes = skip_pass_in_progress(sensor.passes(grid, grid_states), float(grid[0]), say, f" for {key!r}")
            by_key[key] = passes
            times = plan_measurement_times(scenario, scenario.build("schedule", registry), passes, s_rng)
            say(f"observer {key!r}: {len(passes)} passes, {times.size} measurements scheduled")
            if times.size:
                parts.append((key, None, simulate_measurements(sensor, truth.states_at(times), times, n_rng, registry)))
    if not parts:
        raise ConfigError(f"{scenario.source}: no observer saw the target in {scenario.duration_days:g} days "
                          f"(observers: {', '.join(keys)})")
    merged = merge_sites(parts)
    merged.meta.update({"observers": keys})
    for key in keys:                       # an observer that saw nothing still answers for itself
        merged.site_table.setdefault(key, None)
    every = sorted((p for ps in by_key.values() for p in ps), key=lambda p: (p.start, p.end))
    return NetworkObservations(merged, SiteNetwork(members, merged.times, merged.sites), every, by_key)


def iod_input(scenario, measurements: MeasurementSet, sensor: SiteNetwork):
    """The measurements and sensor the IOD works from: those of ``[run] iod_observer``."""
    key = scenario.iod_observer
    rows = np.flatnonzero(measurements.sites == key)
    if rows.size == 0:
        measured = list(measurements.site_keys())
        fix = (f"set [run] iod_observer = {measured[0]!r}" + (f" (observers that measured: {', '.join(measured)})"
                                                             if len(measured) > 1 else "")
               if measured else "no observer took any")
        raise ConfigError(f"{scenario.source}: the IOD works from observer {key!r} ([run] iod_observer, by default the "
                          f"first [sensors] table), which took no measurements; the IOD needs an arc: {fix}")
    return measurements.subset(rows), sensor.subset(rows)
