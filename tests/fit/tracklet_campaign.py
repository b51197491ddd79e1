"""A small survey campaign for the tracklet-IOD tests: a lone first tracklet, then uneven nights.

:func:`survey_campaign` propagates a synodic truth (km, km/s, the real Earth-Moon frame of the
``real-data`` scenario's ephemeris dynamics) and observes it with the ``real-telescope`` sensor
from MPC sites in darkness above 20 deg: the first night one tracklet of 3-5 exposures over
10-30 minutes, then on each later day with probability 0.6 one site's pass with 1-2 tracklets
(starts at least 1 h apart); 3 % gross outliers (at least one, never in the first tracklet)
moved 60-300 arcsec. Every draw comes from ``numpy.random.default_rng(seed)``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.astro.site_network import merge_sites
from cistrack.astro.sites import observatory
from cistrack.plugin.registry import default_registry
from cistrack.runs.observation_files import write_observations
from cistrack.scenario.loading import load_scenario
from cistrack.units import ARCSEC_RAD

__all__ = ["Campaign", "survey_campaign", "heo_state_km"]


@dataclass
class Campaign:
    """path: the ADES PSV written; epoch: UTC of t = 0 of ``x0`` (synodic LU, VU); dynamics: the
    model the truth was propagated with; outliers: UTC text (to the second) of the displaced ones;
    n: observations."""

    path: Path
    epoch: object
    x0: np.ndarray
    dynamics: object
    outliers: list
    n: int


def heo_state_km(perigee_km: float = 70_000.0, apogee_km: float = 600_000.0, anomaly_deg: float = -40.0,
                 incl_deg: float = 20.0) -> np.ndarray:
    """Synodic state (6,) km, km/s of a geocentric ellipse (perigee away from the Moon, plane
    inclined about the synodic x axis) at a true anomaly: v_syn = v_inertial - omega x r."""
    mu_e = 398600.4418
    a, e = 0.5 * (perigee_km + apogee_km), (apogee_km - perigee_km) / (apogee_km + perigee_km)
    p = a * (1.0 - e * e)
    nu, i = np.radians(anomaly_deg), np.radians(incl_deg)
    r = p / (1.0 + e * np.cos(nu))
    u = nu + np.pi
    vr, vt = np.sqrt(mu_e / p) * e * np.sin(nu), np.sqrt(mu_e / p) * (1.0 + e * np.cos(nu))
    rot = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(i), -np.sin(i)], [0.0, np.sin(i), np.cos(i)]])
    pos = rot @ np.array([r * np.cos(u), r * np.sin(u), 0.0])
    vel = rot @ np.array([vr * np.cos(u) - vt * np.sin(u), vr * np.sin(u) + vt * np.cos(u), 0.0])
    omega = 2.0 * np.pi / (27.321661 * 86400.0)
    vel = vel - np.cross([0.0, 0.0, omega], pos)
    earth = -1.2150582e-2 * units.LU_KM
    return np.concatenate([pos + [earth, 0.0, 0.0], vel])


def _sensor(scen, reg, code: str):
    site = observatory(code)
    params = dict(scen.components["sensor"].params)
    params.update(latitude_deg=float(site.latitude_deg), longitude_deg=float(site.longitude_deg),
                  height_m=float(site.height_m), measure_range=False, elevation_mask_deg=20.0,
                  visibility={"sun_max_elevation_deg": -12.0})
    return reg.create("sensor", "real-telescope", **params), site


def _tracklet(rng: np.random.Generator, start: float) -> np.ndarray:
    n = int(rng.integers(3, 6))
    return start + np.linspace(0.0, rng.uniform(10.0, 30.0), n) * 60.0 / units.TU_S


def _plan(rng, passes, days: float, first_night: int) -> dict[str, list[np.ndarray]]:
    """Tracklet times (TU) per site; ``passes``: (site, pass) by start; ``first_night``
    tracklets (1 h apart) in the first pass."""
    usable = [(c, p) for c, p in passes if (p.end - p.start) * units.TU_S >= 2400.0 * first_night]
    site0, p0 = usable[0]
    hour = 3600.0 / units.TU_S
    out = {site0: [_tracklet(rng, p0.start + 0.1 * hour + k * hour) for k in range(first_night)]}
    day = 86400.0 / units.TU_S
    for k in range(1, int(days)):
        tonight = [(c, p) for c, p in usable if p0.start + (k - 0.25) * day <= p.start < p0.start + (k + 0.75) * day]
        if not tonight or rng.uniform() > 0.6:
            continue
        code, pas = tonight[int(rng.integers(len(tonight)))]
        room = pas.end - pas.start - 1800.0 / units.TU_S
        starts = pas.start + np.unique(np.round(np.sort(rng.uniform(0.0, 1.0, int(rng.integers(1, 3)))) * 4) / 4) * room
        out.setdefault(code, []).extend(_tracklet(rng, s) for s in starts)
    return out


def _displace(rng, ms, first: int) -> list[int]:
    n = max(1, int(round(0.03 * len(ms))))
    rows = np.sort(rng.choice(np.arange(first, len(ms)), size=n, replace=False))
    for i in rows:
        d, ang = rng.uniform(60.0, 300.0) * ARCSEC_RAD, rng.uniform(0.0, 2.0 * np.pi)
        ms.values[i, 0] += d * np.cos(ang) / np.cos(ms.values[i, 1])
        ms.values[i, 1] += d * np.sin(ang)
    return [int(i) for i in rows]


def survey_campaign(out: Path, state_km, epoch: str, sites: tuple[str, ...], seed: int, days: float = 12.0,
                    sigma_arcsec: float = 0.7, first_night: int = 1) -> Campaign:
    """Simulate and write ``out``/observations.psv (see the module docstring); ``first_night``:
    tracklets in the first night (``days`` = 1 and 3: a file of one night)."""
    reg = default_registry()
    scen = load_scenario("real-data").with_overrides({
        "epoch": epoch, "duration_days": days + 1.0, "truth": {"state_km": [float(v) for v in state_km]},
        "sensor": {"sigma_arcsec": float(sigma_arcsec)}})
    dyn = scen.build("dynamics", reg)
    x0 = scen.initial_truth(reg)
    grid = np.linspace(0.0, scen.duration, int(scen.duration_days * 144) + 1)
    truth = np.concatenate([x0[None], dyn.propagate(x0[None], 0.0, grid[1:]).states[:, 0]])
    sensors = {c: _sensor(scen, reg, c) for c in sites}
    passes = sorted(((c, p) for c in sites for p in sensors[c][0].passes(grid, truth) if p.start > 0.0),
                    key=lambda cp: cp[1].start)
    rng = np.random.default_rng(seed)
    plan = _plan(rng, passes, days, first_night)
    parts = []
    for code, tracklets in plan.items():
        times = np.sort(np.concatenate(tracklets))
        states = dyn.propagate(x0[None], 0.0, times).states[:, 0]
        parts.append((code, sensors[code][1], sensors[code][0].simulate(states, times, rng)))
    ms = merge_sites(parts)
    first = len(next(iter(plan.values()))[0])
    rows = _displace(rng, ms, first)
    ms.meta["object"] = "sim"
    out.mkdir(parents=True, exist_ok=True)
    write_observations(out / "observations.psv", ms, scen.epoch, format="ades-psv")
    utc = [units.format_utc(units.tu_to_utc(scen.epoch, float(ms.times[i])))[:19] for i in rows]
    return Campaign(out / "observations.psv", scen.epoch, x0, dyn, utc, len(ms))
