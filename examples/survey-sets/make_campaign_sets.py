"""Simulate dense follow-up campaigns of a cislunar object, with or without a burn, and their truth.

    .venv/bin/python examples/survey-sets/make_campaign_sets.py --out DIR [--family NAME ...] [--seed N ...]
        [--burn-ms DV | --burn-range LO HI] [--days D]

A campaign is what a follow-up network sends about an object it tracks: three sites (two in the
north, one in the south, MPC codes of ``make_survey_sets.NORTH`` and ``SOUTH``) observing it on
every dark pass of ``--days`` days (14 by default), one exposure every 10-20 minutes through each
pass above 20 deg elevation with the Sun below -12 deg. Noise 0.5-1.0 arcsec (one value per set),
1 % gross outliers of 30-300 arcsec (at least one). The truth flies the family's orbit in
cistrack's ephemeris dynamics from an epoch drawn in 2026 (``make_survey_sets._choose``).

With ``--burn-ms DV`` the object makes one impulsive burn of DV m/s (``--burn-range LO HI``: a
size drawn evenly in [LO, HI]) in an isotropic random direction (synodic frame) at a time drawn
evenly between 2 days after the first observation and 1 day before the last: between nights or
within one. The layout is ``make_survey_sets.py``'s (observations.psv, truth.csv, set.json with
``burn``), so ``check_survey_fit.py`` fits and scores these sets too.

Every random draw comes from ``numpy.random.default_rng`` streams split from (seed, family,
"campaign"); same family and seed, same files. Seeds are shared with no other generator.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_survey_sets as survey  # noqa: E402  (the sibling generator: families, sensors, truth)

from cistrack import units  # noqa: E402
from cistrack.astro.site_network import merge_sites  # noqa: E402
from cistrack.interfaces.maneuvers import Impulse  # noqa: E402
from cistrack.plugin.registry import default_registry  # noqa: E402
from cistrack.propagation.impulses import ImpulsiveDynamics  # noqa: E402
from cistrack.runs.observation_files import write_observations  # noqa: E402

OUTLIER_FRACTION = 0.01
CADENCE_MIN = (10.0, 20.0)
MIN_PASS_MIN = 30.0
CAMPAIGN_STREAM = 7  # tells these streams from make_survey_sets.py's of the same seed


def _sites(rng: np.random.Generator) -> list[str]:
    north = [str(c) for c in rng.choice(survey.NORTH, size=2, replace=False)]
    return north + [str(rng.choice(survey.SOUTH))]


def _pass_times(rng: np.random.Generator, pas) -> np.ndarray:
    """Exposure times (TU) through one pass, every 10-20 minutes from a random phase."""
    lo, hi = (c / 60.0 * 3600.0 / units.TU_S for c in CADENCE_MIN)
    t = pas.start + rng.uniform(0.0, lo)
    out = []
    while t < pas.end:
        out.append(t)
        t += rng.uniform(lo, hi)
    return np.array(out)


def plan(rng: np.random.Generator, scen, reg, sites: list[str], grid, truth) -> dict[str, np.ndarray]:
    """Exposure times per site over every dark pass of at least ``MIN_PASS_MIN`` minutes."""
    out: dict[str, np.ndarray] = {}
    for code in sites:
        sensor, _site = survey._sensor(scen, reg, code)
        passes = [p for p in sensor.passes(grid, truth)
                  if p.start > grid[0] + 1e-12 and (p.end - p.start) * units.TU_S >= MIN_PASS_MIN * 60.0]
        times = [_pass_times(rng, p) for p in passes]
        if times:
            out[code] = np.sort(np.concatenate(times))
    return out


def _burn(rng: np.random.Generator, t_first: float, t_last: float, dv_ms: float, epoch) -> tuple[Impulse, dict]:
    """One burn of ``dv_ms`` in an isotropic direction at a time drawn evenly in
    [first + 2 d, last - 1 d]; (the impulse, its record)."""
    day = 86400.0 / units.TU_S
    t_burn = float(rng.uniform(t_first + 2.0 * day, t_last - day))
    u = rng.standard_normal(3)
    dv = u / np.linalg.norm(u) * dv_ms
    record = {"utc": units.format_utc(units.tu_to_utc(epoch, t_burn)), "delta_v_ms": float(dv_ms),
              "delta_v_vector_ms": [float(v) for v in dv], "frame": "synodic"}
    return Impulse(t_burn, dv / (units.vu_to_kms(1.0) * 1000.0), "burn"), record


def _draw(family: str, seed: int, rng: np.random.Generator, reg, days: float):
    """Epochs, sites and noise drawn until the truth flies ``days`` days without hitting a body."""
    for _k in range(survey.MAX_DRAWS):
        info = survey._choose(rng, family, seed)
        info.update(sites=_sites(rng), span_days=float(days))
        scen = survey._scenario(family, info["epoch"], days, info["sigma_arcsec"])
        made = survey._truth(scen, reg)
        if made is not None:
            return info, scen, made
    raise SystemExit(f"make_campaign_sets: no {family} truth flies {days:g} days in {survey.MAX_DRAWS} draws (seed {seed})")


def make(out: Path, family: str, seed: int, burn_ms: float = 0.0, days: float = 14.0) -> dict:
    """Simulate one campaign into ``out``; returns its description (also written as set.json)."""
    streams = np.random.SeedSequence([seed, survey.FAMILIES.index(family), CAMPAIGN_STREAM]).spawn(5)
    choose_rng, plan_rng, noise_rng, outlier_rng, burn_rng = (np.random.default_rng(s) for s in streams)
    reg = default_registry()
    info, scen, (dyn, x0, grid, truth) = _draw(family, seed, choose_rng, reg, days)
    times = plan(plan_rng, scen, reg, info["sites"], grid, truth)
    if not times:
        raise SystemExit(f"make_campaign_sets: {family} seed {seed}: no site sees the object")
    everything = np.concatenate(list(times.values()))
    if burn_ms > 0:
        impulse, info["burn"] = _burn(burn_rng, float(everything.min()), float(everything.max()), burn_ms, scen.epoch)
        dyn = ImpulsiveDynamics(dyn, [impulse])
    parts = []
    for code, t in times.items():
        sensor, site = survey._sensor(scen, reg, code)
        parts.append((code, site, sensor.simulate(dyn.propagate(x0[None], 0.0, t).states[:, 0, :], t, noise_rng)))
    ms = merge_sites(parts)
    rows = survey._displace(outlier_rng, ms, 8, OUTLIER_FRACTION)
    ms.meta["object"] = family
    out.mkdir(parents=True, exist_ok=True)
    write_observations(out / "observations.psv", ms, scen.epoch, format="ades-psv")
    survey._write_truth(out / "truth.csv", dyn, x0, float(ms.times[0]), float(ms.times[-1]), scen.epoch, family)
    utc = [units.format_utc(units.tu_to_utc(scen.epoch, ms.times[i])) for i in range(len(ms))]
    info.update(kind="campaign", epoch=units.format_utc(scen.epoch), n_observations=len(ms),
                per_site={code: int(t.size) for code, t in times.items()}, first_utc=utc[0], last_utc=utc[-1],
                outliers=[{"utc": utc[i], "site": str(ms.sites[i])} for i in rows])
    (out / "set.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--family", nargs="+", default=["nrho"], choices=survey.FAMILIES)
    ap.add_argument("--seed", type=int, nargs="+", default=[1])
    ap.add_argument("--days", type=float, default=14.0, help="span of the campaign (default 14)")
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--burn-ms", type=float, default=0.0, help="one impulsive burn of this many m/s (default: none)")
    size.add_argument("--burn-range", type=float, nargs=2, metavar=("LO", "HI"),
                      help="one burn of a size drawn evenly in [LO, HI] m/s")
    a = ap.parse_args()
    for fam in a.family:
        for seed in a.seed:
            dv = a.burn_ms
            if a.burn_range:
                rng = np.random.default_rng([seed, survey.FAMILIES.index(fam), CAMPAIGN_STREAM, 1])
                dv = round(float(rng.uniform(*a.burn_range)), 3)
            info = make(a.out / f"{fam}-c{seed}", fam, seed, dv, a.days)
            burn = f"; a {dv:g} m/s burn at {info['burn']['utc'][:16]}" if "burn" in info else ""
            print(f"{fam} seed {seed}: {info['n_observations']} observations {info['per_site']} from "
                  f"{info['first_utc'][:16]} to {info['last_utc'][:16]}; {len(info['outliers'])} outliers{burn}")


if __name__ == "__main__":
    main()
