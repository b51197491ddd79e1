"""How often a run's burn estimates agree with the truth they estimate (issue 52).

Runs a scenario with burns in its truth over a range of seeds (two processes) and compares each
estimate in ``summary.maneuvers`` with the nearest burn of ``summary.truth_maneuvers``: the burn
time's z-score (estimate - truth) / t_burn_sigma_days, and the delta-v vector's squared
Mahalanobis distance from the truth in the estimate's covariance (chi-square of 3 dof when the
covariance is honest: 14.2 is its 0.997 quantile). A confirmed estimate is inconsistent when its
|z| exceeds 3 or its distance 14.2.

    .venv/bin/python benchmarks/burn_consistency.py example-1-maneuver --seeds 3680 3709

prints a line per estimate (seed, confirmed, z, distance, the unconfirmed reason's first words)
and the counts.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np

CHI2_3_0997 = 14.16
"""The chi-square quantile of 3 degrees of freedom at 0.997 (3 sigma of one)."""


def _maneuvers(job: tuple[str, int]) -> tuple[int, list, list]:
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    scenario, seed = job
    s = run_scenario(load_scenario(scenario), seed=seed).summary
    return seed, list(s.maneuvers or []), list(s.truth_maneuvers or [])


def compared(estimate: dict, truths: list[dict]) -> tuple[float, float] | None:
    """(time z-score, vector Mahalanobis^2) of ``estimate`` against its nearest truth burn; None
    when it has no time or delta-v."""
    tb, ts = estimate.get("t_burn_days"), estimate.get("t_burn_sigma_days")
    if not truths or tb is None or not ts or estimate.get("delta_v_vector_ms") is None:
        return None
    truth = min(truths, key=lambda t: abs(t["t_days"] - tb))
    d = np.asarray(estimate["delta_v_vector_ms"]) - np.asarray(truth["delta_v_vector_ms"])
    return (tb - truth["t_days"]) / ts, float(d @ np.linalg.solve(np.asarray(estimate["delta_v_covariance_ms2"]), d))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, nargs=2, required=True, metavar=("FIRST", "LAST"))
    args = ap.parse_args()
    jobs = [(args.scenario, k) for k in range(args.seeds[0], args.seeds[1] + 1)]
    n = confirmed = bad = 0
    with ProcessPoolExecutor(2) as pool:
        for seed, estimates, truths in pool.map(_maneuvers, jobs):
            for e in estimates:
                n += 1
                zm = compared(e, truths)
                why = (e.get("unconfirmed_reason") or "")[:50]
                print(f"{seed} confirmed={e.get('confirmed')} " + (f"z={zm[0]:+.2f} M2={zm[1]:.1f} " if zm else "")
                      + why)
                if e.get("confirmed") and zm:
                    confirmed += 1
                    bad += abs(zm[0]) > 3 or zm[1] > CHI2_3_0997
    print(f"{args.scenario} seeds {args.seeds[0]}-{args.seeds[1]}: {n} estimates, {confirmed} confirmed, "
          f"{bad} of them inconsistent with the truth (|z| > 3 or M2 > {CHI2_3_0997})")


if __name__ == "__main__":
    main()
