"""Compare a run's exported estimate with the truth the observations were simulated from.

    .venv/bin/python examples/real-data/compare.py runs/real-data [--truth cistrack/scenarios/real_data/truth.csv]

Propagates the truth (first row of truth.csv) to every step of the run and maps it into the run's export frame with the same transform
as the export, at every step of the run, and prints the position/velocity error, the reported
3-sigma and the Mahalanobis distance (chi-square with 6 degrees of freedom if consistent), then
the run's NIS test (measurement consistency, no truth needed).
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from cistrack import units
from cistrack.evaluation.consistency import run_nis_test
from cistrack.runs.export import run_inertial_estimates
from cistrack.scenario.loading import builtin_scenario_path


def truth_at(truth_csv: Path, scen, t_tu: np.ndarray) -> np.ndarray:
    """Truth states (nondimensional synodic) at ``t_tu``: the first row of ``truth_csv``
    propagated with the scenario's truth dynamics (the model the observations came from)."""
    from cistrack.plugin.registry import default_registry
    rows = [r for r in csv.reader(line for line in truth_csv.read_text().splitlines() if not line.startswith("#"))][1:]
    t0 = units.utc_to_tu(scen.epoch, units.parse_utc(rows[0][0]))
    x0 = units.state_from_km(np.array([float(v) for v in rows[0][1:]]))
    spec = scen.truth_dynamics or scen.components["dynamics"]
    dyn = spec.build(default_registry())
    order = np.argsort(t_tu)
    out = np.empty((len(t_tu), 6))
    out[order] = dyn.propagate(x0[None], t0, np.asarray(t_tu)[order]).states[:, 0, :]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--truth", type=Path, default=builtin_scenario_path("real-data").parent / "real_data" / "truth.csv")
    a = ap.parse_args()
    est, scen = run_inertial_estimates(a.run)
    truth = est.frame.from_synodic(truth_at(a.truth, scen, est.t_tu), est.t_tu)
    print(f"frame {est.frame.name}; {len(est.utc)} steps; 3-sigma Mahalanobis bound {chi2.ppf(0.9973, 6):.1f}")
    print(f"{'utc':20} {'kind':8} {'pos err km':>10} {'3 sigma pos km (x, y, z)':>28} {'vel err m/s':>11} {'Mahalanobis':>11}")
    inside = 0
    for k in range(len(est.utc)):
        e = truth[k] - est.state_km[k]
        sd = np.sqrt(np.diag(est.covariance_km[k]))
        m = float(e @ np.linalg.solve(est.covariance_km[k], e))
        inside += bool(np.all(np.abs(e) <= 3 * sd))
        print(f"{est.utc[k][:19]:20} {est.kind[k]:8} {np.linalg.norm(e[:3]):10.2f} "
              f"{'(' + ', '.join(f'{3 * s:.1f}' for s in sd[:3]) + ')':>28} {1000 * np.linalg.norm(e[3:]):11.2f} {m:11.2f}")
    print(f"{inside} of {len(est.utc)} steps within 3 sigma on every axis")
    print(run_nis_test(a.run))


if __name__ == "__main__":
    main()
