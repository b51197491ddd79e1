"""Simulated observation campaigns for the arc and determination tests: the 9:2 NRHO of the
built-in ``real-data`` scenario (ephemeris dynamics, ``real-telescope`` RA/Dec, 1.0 arcsec, the
``paper-example-1`` schedule at each site), observed from MPC observatories as
``examples/real-data/make_observations.py`` does (``simulate_sites``).

- :func:`one_night`: one night from one site (MPC 711);
- :func:`two_weeks`: 14 days from three sites (711, 809, 568; the NRHO of this scenario hits the
  Moon on day 16 in the ephemeris model);
- :func:`two_arcs`: two arcs of 4 days from 711 and 809, ``gap_days`` apart, of the 2:1 distant
  retrograde orbit (stable for months) or of another catalog orbit; with ``dv_mps`` the
  later arc observes the orbit after a velocity change of that size at the middle of the gap (no
  single orbit explains both arcs: a broken link, as a close lunar flyby or a manoeuvre makes).

Each returns a :class:`Campaign`: the merged measurements (TU since the first arc's epoch), the
fit's dynamics and site network, and the truth as a function of time (for the later arc's truth
after a velocity change: its own orbit).
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import timedelta
from functools import lru_cache
from typing import Callable

import numpy as np

from cistrack import units
from cistrack.astro.site_network import build_site_network
from cistrack.astro.site_simulation import simulate_sites
from cistrack.astro.sites import observatory
from cistrack.fitting.arcs import in_time_base
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import load_scenario


@dataclass(frozen=True)
class Campaign:
    measurements: MeasurementSet     # (K, 2) RA/Dec rad, per-row MPC site, TU since ``epoch``
    dynamics: object                 # ephemeris dynamics of the scenario at ``epoch``
    sensor: object                   # site network over the measurements
    truth_at: Callable               # times (J,) TU -> truth (J, 6) LU, VU (the latest arc's orbit)
    epoch: object                    # datetime of t = 0


def _scenario(days: float, start_hours: float = 0.0, state=None, orbit: str = "nrho-9-2"):
    """The ``real-data`` scenario, ``days`` long, starting ``start_hours`` after its epoch, with
    the truth ``state`` (6,) LU, VU there when given (else the catalog ``orbit`` propagated)."""
    scen = load_scenario("real-data").with_overrides({"truth": {"orbit": orbit}})
    over: dict = {"duration_days": float(days)}
    if start_hours:
        dyn = scen.build("dynamics", default_registry())
        t = float(units.hours_to_tu(start_hours))
        x = dyn.propagate(scen.initial_truth()[None], 0.0, np.array([t])).states[0, 0] if state is None else state
        over["truth"] = {"state_km": [float(v) for v in units.state_to_km(x)]}
        over["epoch"] = units.format_utc(scen.epoch + timedelta(hours=start_hours))
    return scen.with_overrides(over)


def _campaign(scen, sites, seed) -> tuple[MeasurementSet, object]:
    camp = simulate_sites(scen, {code: observatory(code) for code in sites}, seed=seed)
    return camp.measurements, camp


def _finish(ms: MeasurementSet, scen0, truth_at) -> Campaign:
    reg = default_registry()
    return Campaign(ms, scen0.build("dynamics", reg), build_site_network(scen0.components["sensor"], reg, ms),
                    truth_at, scen0.epoch)


@lru_cache(maxsize=2)
def one_night(seed: int = 21) -> Campaign:
    """One night (the first pass, every 40-60 min) from MPC 711 (McDonald)."""
    scen = _scenario(2.0)
    ms, camp = _campaign(scen, ("711",), seed)
    gaps = np.nonzero(np.diff(ms.times) > float(units.hours_to_tu(3.0)))[0]
    night = ms.subset(np.arange(len(ms)) <= gaps[0]) if gaps.size else ms
    return _finish(night, scen, camp.truth_at)


@lru_cache(maxsize=2)
def two_weeks(seed: int = 22) -> Campaign:
    """14 days from MPC 711, 809 (La Silla) and 568 (Mauna Kea)."""
    scen = _scenario(14.0)
    ms, camp = _campaign(scen, ("711", "809", "568"), seed)
    return _finish(ms, scen, camp.truth_at)


def _joined(first: MeasurementSet, later: MeasurementSet, shift: float) -> MeasurementSet:
    """``first`` then ``later`` (its times moved by ``shift`` TU), one set."""
    def cat(a, b):
        return np.concatenate([a, b])
    return MeasurementSet(cat(first.times, later.times + shift), cat(first.values, later.values),
                          cat(first.sigmas, later.sigmas), first.names, dict(first.meta),
                          cat(first.sites, later.sites), cat(first.kinds, later.kinds),
                          {**first.site_table, **later.site_table})


@lru_cache(maxsize=4)
def two_arcs(gap_days: float, dv_mps: float = 0.0, seed: int = 23, arc_days: float = 4.0,
             orbit: str = "dro-2-1") -> Campaign:
    """Two arcs of ``arc_days`` from MPC 711 and 809, the second starting ``gap_days`` after the
    first ends; ``dv_mps``: a velocity change (m/s, along the synodic velocity) at the middle of
    the gap, so that the second arc observes another orbit."""
    reg = default_registry()
    scen_a = _scenario(arc_days, orbit=orbit)
    ms_a, camp_a = _campaign(scen_a, ("711", "809"), seed)
    dyn = scen_a.build("dynamics", reg)
    x0 = scen_a.initial_truth()
    t_kick = float(units.days_to_tu(arc_days + 0.5 * gap_days))
    t_b = float(units.days_to_tu(arc_days + gap_days))
    x_kick = dyn.propagate(x0[None], 0.0, np.array([t_kick])).states[0, 0].copy()
    v = x_kick[3:]
    x_kick[3:] = v + v / np.linalg.norm(v) * units.kms_to_vu(dv_mps * 1e-3)
    x_b = dyn.propagate(x_kick[None], t_kick, np.array([t_b])).states[0, 0]
    scen_b = _scenario(arc_days, 24.0 * (arc_days + gap_days), state=x_b, orbit=orbit)
    ms_b, camp_b = _campaign(scen_b, ("711", "809"), seed + 1)

    def truth_at(times):
        return camp_b.truth_at(np.asarray(times, dtype=float) - t_b)

    return _finish(_joined(ms_a, ms_b, t_b), scen_a, truth_at)


def rebased(c: Campaign, new_epoch) -> Campaign:
    """``c`` with t = 0 at ``new_epoch`` (a datetime): its measurements' times, dynamics, sensor
    and truth counted from there, as ``cistrack fit`` counts them in a scenario that starts at the
    latest arc."""
    reg = default_registry()
    scen = load_scenario("real-data").with_overrides({"epoch": units.format_utc(new_epoch)})
    ms = in_time_base(c.measurements, c.epoch, new_epoch)
    shift = float(units.seconds_to_tu((new_epoch - c.epoch).total_seconds()))

    def truth_at(times):
        return c.truth_at(np.asarray(times, dtype=float) + shift)

    return Campaign(ms, scen.build("dynamics", reg), build_site_network(scen.components["sensor"], reg, ms),
                    truth_at, new_epoch)
