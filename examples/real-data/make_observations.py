"""Simulate the built-in 'real-data' campaign and write its observation files.

    .venv/bin/python examples/real-data/make_observations.py [--out DIR] [--seed N]

Reads the built-in scenario ``real-data`` (its [truth], [dynamics], [sensor] and [schedule]
tables), simulates RA/Dec observations of the truth from two observatories (MPC 711 McDonald,
Texas, and 809 ESO La Silla, Chile) with ``cistrack.astro.site_simulation.simulate_sites``, and writes

    observations.psv   IAU ADES, pipe-separated (what the scenario reads)
    observations.tdm   the same observations as a CCSDS TDM (RADEC)
    truth.csv          the truth every hour (UTC, synodic km and km/s of the scenario's frame)

into DIR (default: the scenario's own folder, cistrack/scenarios/real_data/). Same seed, same
files. Step-by-step walk-through: docs/real-data.md.
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


def make(out: Path, seed: int | None = None):
    """Simulate and write the files into ``out``; returns the SimulatedCampaign."""
    scen = load_scenario("real-data")
    camp = simulate_sites(scen, {code: observatory(code) for code in SITES}, seed=seed)
    out.mkdir(parents=True, exist_ok=True)
    ms = camp.measurements
    ms.meta["object"] = "cis0001"
    write_observations(out / "observations.psv", ms, scen.epoch, format="ades-psv")
    write_observations(out / "observations.tdm", ms, scen.epoch, format="tdm")
    km = units.state_to_km(camp.truth_states)
    with (out / "truth.csv").open("w") as fh:
        fh.write("# truth of the 'real-data' campaign, hourly: synodic frame of the scenario's dynamics, km and km/s\n")
        fh.write("utc,x_km,y_km,z_km,vx_kms,vy_kms,vz_kms\n")
        for t, row in zip(camp.truth_times[::12], km[::12]):
            fh.write(units.format_utc(units.tu_to_utc(scen.epoch, t)) + "," + ",".join(repr(float(v)) for v in row) + "\n")
    counts = {k: int(np.sum(ms.sites == k)) for k in SITES}
    print(f"wrote {len(ms)} observations ({counts}) to {out}")
    return camp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=builtin_scenario_path("real-data").parent / "real_data")
    ap.add_argument("--seed", type=int, default=None)
    a = ap.parse_args()
    make(a.out, a.seed)


if __name__ == "__main__":
    main()
