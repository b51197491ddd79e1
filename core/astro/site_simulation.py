"""Simulating observations of a scenario's truth from several sites at once.

For each site the scenario's sensor is placed there (its ``latitude_deg``, ``longitude_deg``,
``height_m``), its visibility passes of the truth are found, the scenario's schedule plans
measurement times inside them, and the sensor simulates noisy measurements; the sets are merged
into one time-ordered set that names each measurement's site (``cistrack.astro.site_network.merge_sites``).
This is how observation files of a multi-site campaign are made (``docs/real-data.md``).

Random streams: one ``SeedSequence(seed)`` is split per site into a schedule and a noise stream,
so a site's measurements do not change when another site is added.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.interfaces.component import component_name
from cistrack.interfaces.schedule import checked_plan
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry, default_registry
from cistrack.astro.site_network import merge_sites
from cistrack.astro.sites import Site

__all__ = ["simulate_sites", "SimulatedCampaign"]


@dataclass
class SimulatedCampaign:
    """A simulated multi-site campaign.

    Attributes
    ----------
    measurements : MeasurementSet with per-measurement sites (angles only: no range)
    truth_times : (K,) TU grid; truth_states : (K, 6) nondimensional synodic truth on it
    x0 : (6,) truth at t = 0
    """

    measurements: MeasurementSet
    truth_times: np.ndarray
    truth_states: np.ndarray
    x0: np.ndarray
    truth_dynamics: object

    def truth_at(self, times) -> np.ndarray:
        """Truth states (J, 6) at ``times`` (J,) TU, propagated from t = 0 in one call."""
        t = np.asarray(times, dtype=float).reshape(-1)
        order = np.argsort(t)
        prop = self.truth_dynamics.propagate(self.x0[None], 0.0, t[order])
        out = np.empty((t.size, 6))
        out[order] = prop.states[:, 0, :]
        return out


def simulate_sites(scenario, sites: dict[str, Site], seed: int | None = None,
                   registry: Registry | None = None, min_gap_s: float = 1.0) -> SimulatedCampaign:
    """Observations of ``scenario``'s truth from every site of ``sites`` (key -> Site), with the
    scenario's sensor (placed at each site), schedule and truth dynamics. Measurements of two
    sites closer than ``min_gap_s`` seconds keep the first site's."""
    reg = registry or default_registry()
    seed = scenario.seed if seed is None else int(seed)
    spec = scenario.components["sensor"]
    if scenario.components.get("schedule") is None:
        raise ConfigError(f"{scenario.source}: simulating sites needs a [schedule] table")
    truth_dyn = scenario.truth_dynamics.build(reg) if scenario.truth_dynamics else scenario.build("dynamics", reg)
    x0 = scenario.initial_truth(reg)
    n_grid = int(np.ceil(scenario.duration / float(units.hours_to_tu(scenario.truth_grid_minutes / 60.0)))) + 1
    grid = np.linspace(0.0, scenario.duration, n_grid)
    prop = truth_dyn.propagate(x0[None], 0.0, grid[1:])
    if not prop.alive[0]:
        raise ConfigError(f"{scenario.source}: the truth trajectory hits a body")
    truth = np.concatenate([x0[None], prop.states[:, 0, :]], axis=0)
    streams = np.random.SeedSequence(seed).spawn(len(sites))
    parts = []
    taken = np.zeros(0)
    for (key, site), ss in zip(sites.items(), streams):
        sched_rng, noise_rng = (np.random.default_rng(s) for s in ss.spawn(2))
        params = {k: (v.build(reg) if hasattr(v, "build") and hasattr(v, "kind") else v) for k, v in spec.params.items()}
        params.update(latitude_deg=float(site.latitude_deg), longitude_deg=float(site.longitude_deg),
                      height_m=float(site.height_m), measure_range=False)
        sensor = reg.create("sensor", spec.name, **params)
        passes = sensor.passes(grid, truth)
        if passes and passes[0].start <= grid[0] + 1e-12:
            passes = passes[1:]
        schedule = scenario.build("schedule", reg)
        times = checked_plan(schedule.plan(passes, scenario.duration, sched_rng), passes, scenario.duration,
                             f"{scenario.source}: [schedule] '{component_name(schedule)}': plan() for site {key}")
        if taken.size and times.size:
            near = np.min(np.abs(times[:, None] - taken[None, :]), axis=1) * units.TU_S < min_gap_s
            times = times[~near]
        if times.size == 0:
            continue
        states = truth_dyn.propagate(x0[None], 0.0, times).states[:, 0, :]
        ms = sensor.simulate(states, times, noise_rng)
        parts.append((key, site, ms))
        taken = np.concatenate([taken, times])
    if not parts:
        raise ConfigError(f"{scenario.source}: no site saw the target in {scenario.duration_days:g} days")
    merged = merge_sites(parts)
    merged.meta.update({"simulated": True, "seed": seed, "scenario": scenario.name})
    return SimulatedCampaign(merged, grid, truth, x0, truth_dyn)
