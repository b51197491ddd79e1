"""Write a long measurement file: several sites observing a simulated 9:2 NRHO at common times.

Every site measures at the same time tags (a fixed cadence) whenever the target is visible from
it, so most times carry several rows (one filter step each). The truth is the built-in ``quick``
scenario's (9:2 NRHO, CR3BP), its sensor (ground-telescope, 1.5 arcsec, with range) placed at
each site; noise from one seeded Generator. Used by ``bench_long_file.py``:

    .venv/bin/python benchmarks/make_long_measurements.py --rows 400000 --out /tmp/long.csv

Run it with ``cistrack run quick --set measurements.file=/tmp/long.csv`` (the file's epoch is the
scenario's, 2026-01-01T00:00:00Z).
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from cistrack import units
from cistrack.plugins.readers.csv_file import write_measurements
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import load_scenario
from cistrack.astro.site_network import merge_sites
from cistrack.astro.sites import observatory

SITES = ("695", "691", "711", "H01")  # Kitt Peak (two), McDonald, Magdalena Ridge: one region, shared passes


def simulate(rows: int, cadence_s: float, sites: tuple[str, ...], seed: int, max_days: float = 400.0):
    """The first ``rows`` measurements (time order) of every site at a common cadence."""
    reg = default_registry()
    scen = load_scenario("quick")
    dyn = scen.build("dynamics", reg)
    x0 = scen.initial_truth(reg)
    rng = np.random.default_rng(seed)
    sensors = {}
    for code in sites:
        s = observatory(code)
        sensors[code] = reg.create("sensor", "ground-telescope", latitude_deg=s.latitude_deg,
                                   longitude_deg=s.longitude_deg, height_m=s.height_m, measure_range=True)
    dt = float(units.hours_to_tu(cadence_s / 3600.0))
    chunk_days, t0, got, parts = 5.0, dt, 0, {code: [] for code in sites}
    state, t_state = x0, 0.0
    while got < rows and t0 < float(units.days_to_tu(max_days)):
        times = np.arange(t0, t0 + float(units.days_to_tu(chunk_days)), dt)
        prop = dyn.propagate(state[None], t_state, times)
        states = prop.states[:, 0, :]
        for code, sensor in sensors.items():
            vis = np.asarray(sensor.visible(states, times), dtype=bool)
            if vis.any():
                ms = sensor.simulate(states[vis], times[vis], rng)
                parts[code].append(ms)
                got += len(ms)
        state, t_state, t0 = states[-1], float(times[-1]), float(times[-1]) + dt
    merged = merge_sites([(code, observatory(code), _concat(sets)) for code, sets in parts.items() if sets])
    return merged.subset(np.arange(min(rows, len(merged))))


def _concat(sets):
    from cistrack.model.measurement import MeasurementSet
    return MeasurementSet(np.concatenate([m.times for m in sets]), np.concatenate([m.values for m in sets]),
                          np.concatenate([m.sigmas for m in sets]), sets[0].names, dict(sets[0].meta))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=400_000)
    ap.add_argument("--cadence-s", type=float, default=10.0, help="seconds between a site's measurements")
    ap.add_argument("--sites", default=",".join(SITES), help="MPC codes of the bundled table, comma-separated")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    t = time.perf_counter()
    ms = simulate(args.rows, args.cadence_s, tuple(args.sites.split(",")), args.seed)
    write_measurements(args.out, ms, load_scenario("quick").epoch)
    n_times = len(ms.time_groups())
    print(f"wrote {args.out}: {len(ms)} rows at {n_times} times ({len(ms) / n_times:.2f} sites per time), "
          f"{units.tu_to_days(ms.times[-1]):.1f} days, seed {args.seed}, {time.perf_counter() - t:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
