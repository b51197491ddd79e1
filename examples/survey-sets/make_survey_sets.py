"""Simulate survey-cadence observation sets of cislunar orbits, with their truth.

    .venv/bin/python examples/survey-sets/make_survey_sets.py --out DIR [--family NAME ...] [--seed N ...]

For each orbit family and seed, writes into DIR/<family>-s<seed>/

    observations.psv   IAU ADES PSV (rmsRA, rmsDec: the simulated noise), object ``<family>``
    truth.csv          the truth hourly from the first observation: UTC, synodic km and km/s of the
                       real Earth-Moon frame (the frame ``examples/real-data/check_fit.py`` and
                       ``check_survey_fit.py`` compare in)
    set.json           family, seed, sites, noise, nights, tracklets and the injected outliers

The truth is propagated in cistrack's ephemeris dynamics (Earth, Moon, Sun from DE421) and
observed with the ``real-telescope`` sensor (topocentric astrometric RA/Dec, light time, Earth
orientation) from MPC observatories of the bundled list, at least one in each hemisphere, in
darkness (Sun below -12 deg) above 20 deg elevation. The cadence of a survey:

- the first night: one lone tracklet of 3-5 exposures over 10-30 minutes from one site;
- then uneven nights over 1-3 weeks (each day observed with probability 0.55), one site a night,
  1-3 tracklets a night (3-5 exposures over 10-30 minutes each, at least 45 minutes apart);
- at least 4 nights in all (an epoch and sites are drawn again, at most 20 times, until they give
  that: the object near the Moon is out of dark skies for about a week a month);
- noise 0.5-1.0 arcsec on the sky (one value per set, stated in the file);
- 3 % gross outliers (at least one), each moved 30-300 arcsec in a random direction, never in the
  first night's tracklet.

Families (``FAMILIES``): ``dro`` (2:1 distant retrograde orbit), ``halo`` (L1 northern halo,
z amplitude about 8,600 km, corrected in the CR3BP, then made continuous in the ephemeris model by
multiple shooting), ``nrho`` (9:2 L2 southern NRHO), ``heo`` (an Earth orbit of about 70,000 x
600,000 km, Keplerian at the start, inclined 20 deg to the Earth-Moon plane, starting 55 deg
before perigee; its first night is the first dark pass while the object is within 84,000 km of
the Earth, below the IOD's default range floor of 84,328 km). The DRO and NRHO states of the
CR3BP catalog are placed in the real Earth-Moon frame as they are (as the ``real-data`` scenario
does) and then follow the ephemeris model.

With ``--burn-ms DV`` the object makes one impulsive burn of DV m/s in an isotropic random
direction (synodic frame) at a time drawn evenly between the last observation of its second night
and the first of its last night (so between nights or, now and then, within one); the observations
and ``truth.csv`` are of the orbit flown with it, and ``set.json`` gives it as ``burn``
(``utc``, ``delta_v_ms``, ``delta_v_vector_ms``). Without the option the sets are as before.
With ``--burn-before-night MINUTES`` as well, the burn lies that many minutes before the first
observation of the first night that begins after the drawn time (the same draws: the set's
observations are those of the same schedule, of the orbit flown with the moved burn).
With ``--exposures N`` every tracklet holds N exposures (a dense file: N = 6,000 gave 11
tracklets, 66,000 observations); the 3-5 is still drawn, but the jitter draws N values, so the
schedule after the first tracklet differs from the default set's of that seed. With
``--area-to-mass A`` the truth feels solar radiation pressure (C_R A/m = A m^2/kg, the ephemeris
dynamics' cannonball model), and ``set.json`` gives it as ``area_to_mass_m2_kg``, which
``check_survey_fit.py`` propagates the truth with.

Every random draw comes from ``numpy.random.default_rng(seed)`` (one stream per set, split
per use with ``SeedSequence.spawn``). Same family and seed, same files. Seeds looked at while
building: 1-3 (tests/fit/test_survey_sets.py uses 1 and 2); seeds 101-110 are kept unseen for
the final check. ``check_survey_fit.py`` fits the sets and tabulates the results.
"""
from __future__ import annotations

import argparse
import json
import math
from datetime import timedelta
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.astro.site_network import merge_sites
from cistrack.astro.sites import observatory
from cistrack.interfaces.maneuvers import Impulse
from cistrack.plugin.registry import default_registry
from cistrack.propagation.impulses import ImpulsiveDynamics
from cistrack.runs.observation_files import write_observations
from cistrack.scenario.loading import load_scenario
from cistrack.units import ARCSEC_RAD

NORTH = ("G96", "J04", "T08", "568", "711")
SOUTH = ("W68", "M22", "Q62", "809")
HALO_L1 = [0.8233859240241993, 0.0, 0.0224, 0.0, 0.13426618964259013, 0.0]
HALO_PERIOD = 2.746373589773783  # TU; both corrected in the CR3BP (correct_symmetric_orbit, fixed="z")
FAMILIES = ("dro", "halo", "nrho", "heo")
OUTLIER_FRACTION = 0.03
SUN_MAX_ELEVATION_DEG = -12.0
ELEVATION_MASK_DEG = 20.0
MIN_NIGHTS = 4
MAX_DRAWS = 20
HEO_FIRST_NIGHT_MAX_KM = 84_000.0


def heo_state_km(perigee_km=70_000.0, apogee_km=600_000.0, anomaly_deg=-55.0, incl_deg=20.0,
                 perigee_angle_deg=180.0) -> list[float]:
    """Synodic state (km, km/s) of a geocentric Keplerian orbit at true anomaly ``anomaly_deg``.

    The ellipse lies in a plane inclined ``incl_deg`` about the synodic x axis, its perigee at
    ``perigee_angle_deg`` from the Earth-Moon line (180: away from the Moon); the inertial
    velocity is turned into the rotating frame's (v - omega x r, omega = 1 per TU)."""
    mu_e = 398600.4418
    a = 0.5 * (perigee_km + apogee_km)
    e = (apogee_km - perigee_km) / (apogee_km + perigee_km)
    p = a * (1.0 - e * e)
    nu, w, i = (math.radians(v) for v in (anomaly_deg, perigee_angle_deg, incl_deg))
    r = p / (1.0 + e * math.cos(nu))
    u = nu + w
    pos = np.array([r * math.cos(u), r * math.sin(u), 0.0])
    vr, vt = math.sqrt(mu_e / p) * e * math.sin(nu), math.sqrt(mu_e / p) * (1.0 + e * math.cos(nu))
    vel = np.array([vr * math.cos(u) - vt * math.sin(u), vr * math.sin(u) + vt * math.cos(u), 0.0])
    rot = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(i), -math.sin(i)], [0.0, math.sin(i), math.cos(i)]])
    pos, vel = rot @ pos, rot @ vel
    omega = 1.0 / units.TU_S
    vel_rot = vel - np.cross([0.0, 0.0, omega], pos)
    pos_syn = pos + np.array([-MU_EARTH_MOON * units.LU_KM, 0.0, 0.0])  # the Earth sits at x = -mu
    return [float(v) for v in np.concatenate([pos_syn, vel_rot])]


def _truth_table(family: str) -> dict:
    if family == "dro":
        return {"orbit": "dro-2-1"}
    if family == "nrho":
        return {"orbit": "nrho-9-2"}
    if family == "halo":
        return {"state_km": [float(v) for v in units.state_to_km(np.array(HALO_L1))]}
    if family == "heo":
        return {"state_km": heo_state_km()}
    raise SystemExit(f"make_survey_sets: unknown family {family!r}; known: {', '.join(FAMILIES)}")


def _scenario(family: str, epoch: str, days: float, sigma: float, area_to_mass: float = 0.0):
    over = {"epoch": epoch, "duration_days": days, "truth": _truth_table(family),
            "sensor": {"sigma_arcsec": sigma}}
    if area_to_mass:  # solar radiation pressure on the truth, C_R A/m m^2/kg
        over["dynamics"] = {"area_to_mass_m2_kg": area_to_mass}
    scen = load_scenario("real-data").with_overrides(over)
    return _ephemeris_halo(scen, days) if family == "halo" else scen


def _ephemeris_halo(scen, days: float):
    """The L1 halo made continuous in the ephemeris model (multiple shooting over its
    revolutions; the CR3BP state alone leaves the halo within two weeks), started at its first
    patch point: the scenario's epoch moves there."""
    from cistrack.plugins.dynamics.ephemeris_corrector import correct_catalog_orbit
    dyn = scen.build("dynamics", default_registry())
    revs = int(math.ceil(days * 86400.0 / (HALO_PERIOD * units.TU_S))) + 1
    orbit = correct_catalog_orbit(dyn, np.array(HALO_L1), HALO_PERIOD, revs, first=min(revs, 4))
    x = orbit.synodic(dyn)[0]
    epoch = units.tu_to_utc(scen.epoch, float(orbit.times[0])).replace(microsecond=0)
    x = dyn.propagate(x[None], float(orbit.times[0]), np.array([units.utc_to_tu(scen.epoch, epoch)])).states[0, 0]
    return scen.with_overrides({"epoch": units.format_utc(epoch),
                                "truth": {"state_km": [float(v) for v in units.state_to_km(x)]}})


def _sensor(scen, reg, code: str):
    site = observatory(code)
    params = dict(scen.components["sensor"].params)
    params.update(latitude_deg=float(site.latitude_deg), longitude_deg=float(site.longitude_deg),
                  height_m=float(site.height_m), measure_range=False, elevation_mask_deg=ELEVATION_MASK_DEG,
                  visibility={"sun_max_elevation_deg": SUN_MAX_ELEVATION_DEG})
    return reg.create("sensor", "real-telescope", **params), site


def _tracklet(rng: np.random.Generator, start: float, exposures: int | None = None) -> np.ndarray:
    """Times (TU) of one tracklet: 3-5 exposures (or ``exposures``) evenly over 10-30 minutes,
    jittered by <= 20 s."""
    n = int(rng.integers(3, 6))
    n = n if exposures is None else exposures
    span_min = rng.uniform(10.0, 30.0)
    t_min = np.linspace(0.0, span_min, n) + rng.uniform(-1.0 / 3.0, 1.0 / 3.0, n) * (np.arange(n) > 0)
    return start + np.sort(t_min) * 60.0 / units.TU_S


def _night_tracklets(rng: np.random.Generator, pas, count: int, exposures: int | None = None) -> list[np.ndarray]:
    """Up to ``count`` tracklets inside the pass ``pas``, starts at least 45 min apart."""
    step = 45.0 * 60.0 / units.TU_S
    last_start = pas.end - 30.0 * 60.0 / units.TU_S
    if last_start <= pas.start:
        return []
    starts = np.sort(rng.uniform(pas.start, last_start, count))
    kept: list[float] = []
    for s in starts:
        if not kept or s - kept[-1] >= step:
            kept.append(float(s))
    return [_tracklet(rng, s, exposures) for s in kept]


def _passes(scen, reg, sites: tuple[str, ...], grid: np.ndarray, truth: np.ndarray) -> list[tuple[str, object]]:
    """(site, pass) of every site's dark visibility passes, by start time."""
    out = []
    for code in sites:
        sensor, _site = _sensor(scen, reg, code)
        out += [(code, p) for p in sensor.passes(grid, truth) if p.start > grid[0] + 1e-12]
    return sorted(out, key=lambda cp: cp[1].start)


def plan(rng: np.random.Generator, passes, span_days: float, first_ok=None,
         exposures: int | None = None) -> dict[str, list[np.ndarray]] | None:
    """Tracklet times per site: the first night's lone tracklet, then uneven nights.

    ``passes``: (site, pass) by start time (TU); ``span_days``: the campaign's length after the
    first night. The first night is the first pass of at least 40 minutes (for which
    ``first_ok(pass)`` holds, if given); ``exposures``: every tracklet's (None: 3-5 drawn). None
    when there is no such pass."""
    long_enough = [(c, p) for c, p in passes if (p.end - p.start) * units.TU_S >= 2400.0]
    firsts = [(c, p) for c, p in long_enough if first_ok is None or first_ok(p)]
    if not firsts:
        return None
    site0, p0 = firsts[0]
    start = p0.start + rng.uniform(0.0, 0.5) * (p0.end - p0.start - 1800.0 / units.TU_S)
    out: dict[str, list[np.ndarray]] = {site0: [_tracklet(rng, start, exposures)]}
    day = 86400.0 / units.TU_S
    for k in range(1, int(math.ceil(span_days))):
        if rng.uniform() > 0.55:
            continue
        lo, hi = p0.start + (k - 0.25) * day, p0.start + (k + 0.75) * day
        tonight = [(c, p) for c, p in long_enough if lo <= p.start < hi and p.start > p0.end]
        if not tonight:
            continue
        code, pas = tonight[int(rng.integers(len(tonight)))]
        out.setdefault(code, []).extend(_night_tracklets(rng, pas, int(rng.integers(1, 4)), exposures))
    return out


def _displace(rng: np.random.Generator, ms, first_night: int, fraction: float = OUTLIER_FRACTION) -> list[int]:
    """Move ``fraction`` of the measurements (at least one; none of the first ``first_night``) by 30-300"."""
    n = max(1, int(round(fraction * len(ms))))
    rows = np.sort(first_night + rng.choice(len(ms) - first_night, size=n, replace=False))
    for i in rows:
        d = rng.uniform(30.0, 300.0) * ARCSEC_RAD
        ang = rng.uniform(0.0, 2.0 * math.pi)
        dec = ms.values[i, 1]
        ms.values[i, 0] = (ms.values[i, 0] + d * math.cos(ang) / math.cos(dec)) % (2.0 * math.pi)
        ms.values[i, 1] = dec + d * math.sin(ang)
    return [int(i) for i in rows]


def _choose(rng: np.random.Generator, family: str, seed: int) -> dict:
    """The set's random choices: epoch, sites (both hemispheres), noise, span."""
    start = units.parse_utc("2026-01-05T00:00:00Z") + timedelta(days=int(rng.integers(0, 300)),
                                                                 hours=float(rng.uniform(0, 24)))
    n_sites = int(rng.integers(2, 4))
    north = [str(c) for c in rng.choice(NORTH, size=1 if n_sites == 2 else int(rng.integers(1, 3)), replace=False)]
    south = [str(c) for c in rng.choice(SOUTH, size=n_sites - len(north), replace=False)]
    sites = tuple(rng.permutation(north + south).tolist())
    return {"family": family, "seed": seed, "epoch": units.format_utc(start.replace(second=0, microsecond=0)),
            "sites": list(sites), "sigma_arcsec": round(float(rng.uniform(0.5, 1.0)), 3),
            "span_days": round(float(rng.uniform(7.0, 21.0)), 2)}


def _truth(scen, reg):
    """(dynamics, x0, 10-minute grid, truth on it) of a scenario; None if the truth hits a body."""
    dyn = scen.build("dynamics", reg)
    grid = np.arange(0.0, scen.duration, 600.0 / units.TU_S)
    x0 = scen.initial_truth(reg)
    prop = dyn.propagate(x0[None], 0.0, grid[1:])
    if not prop.alive[0]:
        return None
    return dyn, x0, grid, np.concatenate([x0[None], prop.states[:, 0, :]])


def _first_night_rule(family: str, grid: np.ndarray, truth: np.ndarray):
    """For the high Earth orbit: the first night starts inside the IOD's default range floor."""
    if family != "heo":
        return None
    r_km = np.linalg.norm(truth[:, :3] - np.array([-MU_EARTH_MOON, 0.0, 0.0]), axis=1) * units.LU_KM
    return lambda p: float(np.interp(p.start, grid, r_km)) < HEO_FIRST_NIGHT_MAX_KM


def _draw(family: str, seed: int, rngs, reg, exposures: int | None = None, area_to_mass: float = 0.0):
    """Draw epochs, sites and schedules until one gives at least ``MIN_NIGHTS`` nights (and, for
    the HEO, a first night inside the range floor); at most ``MAX_DRAWS`` draws."""
    choose_rng, plan_rng = rngs
    for _k in range(MAX_DRAWS):
        info = _choose(choose_rng, family, seed)
        scen = _scenario(family, info["epoch"], info["span_days"] + 8.0, info["sigma_arcsec"], area_to_mass)
        made = _truth(scen, reg)
        if made is None:
            continue
        dyn, x0, grid, truth = made
        times = plan(plan_rng, _passes(scen, reg, tuple(info["sites"]), grid, truth), info["span_days"],
                     _first_night_rule(family, grid, truth), exposures)
        if times is not None and len(_nights(times)) >= MIN_NIGHTS:
            return info, scen, dyn, x0, times
    raise SystemExit(f"make_survey_sets: no acceptable {family} campaign in {MAX_DRAWS} draws for seed {seed}")


def _nights(times: dict[str, list[np.ndarray]]) -> set[int]:
    starts = np.sort([tr[0] for trs in times.values() for tr in trs])
    return set(np.floor((starts - starts[0]) * units.TU_S / 86400.0 + 0.5).astype(int).tolist())


def _burn(rng: np.random.Generator, times: dict[str, list[np.ndarray]], dv_ms: float, epoch,
          before_night_min: float | None = None) -> tuple[Impulse, dict]:
    """One burn of ``dv_ms`` in an isotropic direction, at a time drawn evenly between the last
    observation of the second night and the first of the last night; with ``before_night_min``,
    that many minutes before the first observation of the first night that begins after the drawn
    time instead; (the impulse, its record)."""
    tracklets = sorted((tr for trs in times.values() for tr in trs), key=lambda tr: tr[0])
    starts = np.array([tr[0] for tr in tracklets])
    night = np.floor((starts - starts[0]) * units.TU_S / 86400.0 + 0.5).astype(int)
    second, last = np.unique(night)[1], night.max()
    lo = max(float(tr[-1]) for tr, n in zip(tracklets, night) if n == second)
    hi = min(float(tr[0]) for tr, n in zip(tracklets, night) if n == last)
    t_burn = float(rng.uniform(lo, hi))
    if before_night_min is not None:
        nxt = min(n for s, n in zip(starts, night) if s > t_burn)
        t_burn = float(min(s for s, n in zip(starts, night) if n == nxt)) - before_night_min * 60.0 / units.TU_S
    u = rng.standard_normal(3)
    dv = u / np.linalg.norm(u) * dv_ms
    record = {"utc": units.format_utc(units.tu_to_utc(epoch, t_burn)), "delta_v_ms": float(dv_ms),
              "delta_v_vector_ms": [float(v) for v in dv], "frame": "synodic"}
    return Impulse(t_burn, dv / (units.vu_to_kms(1.0) * 1000.0), "burn"), record


def make(out: Path, family: str, seed: int, burn_ms: float = 0.0, exposures: int | None = None,
         area_to_mass: float = 0.0, burn_before_night: float | None = None) -> dict:
    """Simulate one set into ``out`` (with ``burn_ms`` > 0: the object makes one burn of that many
    m/s, :func:`_burn`, ``burn_before_night`` minutes before a night's first observation when
    given; with ``exposures``, every tracklet holds that many; with ``area_to_mass``
    (m^2/kg, C_R A/m), the truth feels solar radiation pressure, recorded in set.json as
    ``area_to_mass_m2_kg``); returns its description (also written as set.json)."""
    streams = np.random.SeedSequence([seed, FAMILIES.index(family)]).spawn(5)
    choose_rng, plan_rng, noise_rng, outlier_rng, burn_rng = (np.random.default_rng(s) for s in streams)
    reg = default_registry()
    info, scen, dyn, x0, times = _draw(family, seed, (choose_rng, plan_rng), reg, exposures, area_to_mass)
    if area_to_mass:
        info["area_to_mass_m2_kg"] = float(area_to_mass)
    if burn_ms > 0:
        impulse, info["burn"] = _burn(burn_rng, times, burn_ms, scen.epoch, burn_before_night)
        dyn = ImpulsiveDynamics(dyn, [impulse])
    parts = []
    for code, tracklets in times.items():
        t = np.sort(np.concatenate(tracklets))
        sensor, site = _sensor(scen, reg, code)
        states = dyn.propagate(x0[None], 0.0, t).states[:, 0, :]
        parts.append((code, site, sensor.simulate(states, t, noise_rng)))
    ms = merge_sites(parts)
    first = _first_tracklet_size(times)
    rows = _displace(outlier_rng, ms, first)
    ms.meta["object"] = family
    out.mkdir(parents=True, exist_ok=True)
    write_observations(out / "observations.psv", ms, scen.epoch, format="ades-psv")
    _write_truth(out / "truth.csv", dyn, x0, float(ms.times[0]), float(ms.times[-1]), scen.epoch, family)
    utc = [units.format_utc(units.tu_to_utc(scen.epoch, ms.times[i])) for i in range(len(ms))]
    info.update(epoch=units.format_utc(scen.epoch), n_observations=len(ms), first_night_exposures=first,
                nights=len(_nights(times)), tracklets=sum(len(v) for v in times.values()),
                first_utc=utc[0], last_utc=utc[-1],
                outliers=[{"utc": utc[i], "site": str(ms.sites[i])} for i in rows],
                range_km_first=float(_range_km(scen, reg, ms, x0, dyn)))
    (out / "set.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def _first_tracklet_size(times: dict[str, list[np.ndarray]]) -> int:
    firsts = [tr for trs in times.values() for tr in trs]
    return len(min(firsts, key=lambda tr: tr[0]))


def _range_km(scen, reg, ms, x0, dyn) -> float:
    """Geocentric distance of the truth at the first observation, km."""
    x = dyn.propagate(x0[None], 0.0, np.array([float(ms.times[0])])).states[0, 0]
    return float(np.linalg.norm((x[:3] - np.array([-MU_EARTH_MOON, 0.0, 0.0])) * units.LU_KM))


def _write_truth(path: Path, dyn, x0, t_first: float, t_last: float, epoch, family: str) -> None:
    """The truth hourly from the first observation to an hour past the last."""
    t = np.arange(t_first, t_last + 3600.0 / units.TU_S, 3600.0 / units.TU_S)
    km = units.state_to_km(dyn.propagate(x0[None], 0.0, t).states[:, 0, :])
    with path.open("w") as fh:
        fh.write(f"# truth of the survey set '{family}', hourly from the first observation: synodic frame of the "
                 "real Earth-Moon rotating frame (ephemeris dynamics), km and km/s\n")
        fh.write("utc,x_km,y_km,z_km,vx_kms,vy_kms,vz_kms\n")
        for tk, row in zip(t, km):
            fh.write(units.format_utc(units.tu_to_utc(epoch, tk)) + "," + ",".join(repr(float(v)) for v in row) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--family", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    ap.add_argument("--seed", type=int, nargs="+", default=[1])
    ap.add_argument("--burn-ms", type=float, default=0.0, help="one impulsive burn of this many m/s (default: none)")
    ap.add_argument("--exposures", type=int, default=None,
                    help="exposures in every tracklet (default: 3-5 drawn); the schedule is then another one")
    ap.add_argument("--area-to-mass", type=float, default=0.0, metavar="M2_KG",
                    help="solar radiation pressure on the truth, C_R A/m in m^2/kg (default: none)")
    ap.add_argument("--burn-before-night", type=float, default=None, metavar="MINUTES",
                    help="with --burn-ms: the burn this many minutes before the first observation of the first "
                         "night after the time drawn (default: the drawn time)")
    a = ap.parse_args()
    if a.burn_before_night is not None and a.burn_ms <= 0:
        ap.error("--burn-before-night needs --burn-ms")
    for fam in a.family:
        for seed in a.seed:
            info = make(a.out / f"{fam}-s{seed}", fam, seed, a.burn_ms, a.exposures, a.area_to_mass,
                        a.burn_before_night)
            burn = f"; a {a.burn_ms:g} m/s burn at {info['burn']['utc'][:16]}" if "burn" in info else ""
            print(f"{fam} seed {seed}: {info['n_observations']} observations, {info['tracklets']} tracklets over "
                  f"{info['nights']} nights from {', '.join(info['sites'])}; first night {info['first_night_exposures']} "
                  f"exposures at {info['range_km_first']:.0f} km; {len(info['outliers'])} outliers{burn}")


if __name__ == "__main__":
    main()
