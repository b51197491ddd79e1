"""Simulate the built-in 'real-data' campaign and write its observation files.

    .venv/bin/python examples/real-data/make_observations.py [--out DIR] [--seed N]
        [--sigma-arcsec S] [--days D] [--sites CODE CODE ...] [--start-hours H] [--all-formats]

Reads the built-in scenario ``real-data`` (its [truth], [dynamics], [sensor] and [schedule]
tables), simulates RA/Dec observations of the truth from two observatories (MPC 711 McDonald,
Texas, and 809 ESO La Silla, Chile) with ``cistrack.astro.site_simulation.simulate_sites``, and writes

    observations.psv   IAU ADES, pipe-separated (what the scenario reads)
    observations.tdm   the same observations as a CCSDS TDM (RADEC)
    truth.csv          the truth every hour (UTC, synodic km and km/s of the scenario's frame)

into DIR (default: the scenario's own folder, cistrack/scenarios/real_data/). Same seed, same
files. The options change the campaign (the shipped files use none of them): the noise per angle
(``--sigma-arcsec``, the scenario's 1.0 by default), the span (``--days``), the observatories
(``--sites``, MPC codes of the bundled list), where on the orbit the campaign starts (``--start-hours``
after the scenario's epoch: the truth is propagated there first) and, with ``--all-formats``, the
same observations also as ADES XML (``observations.xml``) and MPC 80-column (``observations.obs``,
which carries no uncertainties). Step-by-step walk-through: docs/real-data.md.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.runs.observation_files import write_observations
from cistrack.scenario.loading import builtin_scenario_path, load_scenario
from cistrack.astro.site_simulation import simulate_sites
from cistrack.astro.sites import observatory

SITES = ("711", "809")


def _scenario(sigma_arcsec: float | None, days: float | None, start_hours: float):
    """The 'real-data' scenario with the campaign's changes (none: as shipped)."""
    scen = load_scenario("real-data")
    over: dict = {}
    if sigma_arcsec is not None:
        over["sensor"] = {"sigma_arcsec": float(sigma_arcsec)}
    if days is not None:
        over["duration_days"] = float(days)
    if start_hours:
        from datetime import timedelta

        from cistrack.plugin.registry import default_registry
        dyn = scen.build("dynamics", default_registry())
        t = float(units.hours_to_tu(start_hours))
        x = dyn.propagate(scen.initial_truth()[None], 0.0, np.array([t])).states[0, 0]
        over["truth"] = {"state_km": [float(v) for v in units.state_to_km(x)]}
        over["epoch"] = units.format_utc(scen.epoch + timedelta(hours=start_hours))
    return scen.with_overrides(over) if over else scen


def make(out: Path, seed: int | None = None, sigma_arcsec: float | None = None, days: float | None = None,
         sites: tuple[str, ...] = SITES, start_hours: float = 0.0, all_formats: bool = False):
    """Simulate and write the files into ``out``; returns the SimulatedCampaign."""
    scen = _scenario(sigma_arcsec, days, start_hours)
    camp = simulate_sites(scen, {code: observatory(code) for code in sites}, seed=seed)
    out.mkdir(parents=True, exist_ok=True)
    ms = camp.measurements
    ms.meta["object"] = "cis0001"
    write_observations(out / "observations.psv", ms, scen.epoch, format="ades-psv")
    write_observations(out / "observations.tdm", ms, scen.epoch, format="tdm")
    if all_formats:
        write_observations(out / "observations.xml", ms, scen.epoch, format="ades-xml")
        write_observations(out / "observations.obs", ms, scen.epoch, format="mpc80")
    km = units.state_to_km(camp.truth_states)
    with (out / "truth.csv").open("w") as fh:
        fh.write("# truth of the 'real-data' campaign, hourly: synodic frame of the scenario's dynamics, km and km/s\n")
        fh.write("utc,x_km,y_km,z_km,vx_kms,vy_kms,vz_kms\n")
        for t, row in zip(camp.truth_times[::12], km[::12]):
            fh.write(units.format_utc(units.tu_to_utc(scen.epoch, t)) + "," + ",".join(repr(float(v)) for v in row) + "\n")
    counts = {k: int(np.sum(ms.sites == k)) for k in sites}
    print(f"wrote {len(ms)} observations ({counts}) to {out}")
    return camp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=builtin_scenario_path("real-data").parent / "real_data")
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--sigma-arcsec", type=float, default=None, help="noise per angle (default the scenario's 1.0)")
    ap.add_argument("--days", type=float, default=None, help="span of the campaign (default the scenario's 6)")
    ap.add_argument("--sites", nargs="+", default=list(SITES), help="MPC observatory codes (default 711 809)")
    ap.add_argument("--start-hours", type=float, default=0.0, help="start this long after the scenario's epoch")
    ap.add_argument("--all-formats", action="store_true", help="also write ADES XML and MPC 80-column")
    a = ap.parse_args()
    make(a.out, a.seed, a.sigma_arcsec, a.days, tuple(a.sites), a.start_hours, a.all_formats)


if __name__ == "__main__":
    main()
