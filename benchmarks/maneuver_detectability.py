"""The information bound of burn detection: how large a burn the data of the passes after it can
reveal, whatever the detector (issue 52).

For each seed the scenario is run (no response, so the filter's posteriors are those of a filter
that does not know of the burn). For each truth burn, the measurements from the filter's settled
posterior about a day before the burn to the end of the ``passes`` observed passes after it are
fitted by least squares with the state's prior (that posterior) and an impulsive delta-v at the
burn's TRUE time as unknowns (cistrack.least_squares.impulse_fit.fit_impulses): the delta-v's
covariance C is then what these measurements can tell about any burn at that time. A test of
``dv = 0`` at false-alarm probability ``alpha`` (chi-square, 3 dof) detects a burn dv with the
probability of a noncentral chi-square with noncentrality dv^T C^-1 dv; the burn detected with
probability 0.9 along the truth's direction u has |dv|_90 = sqrt(lambda_90 / (u^T C^-1 u)). This
is a bound: it knows the burn's time, which a detector does not.

    .venv/bin/python benchmarks/maneuver_detectability.py example-1-maneuver --seeds 9301 9302 ... --passes 2

Each row also gives the run's own detector on the burn (``next``: its first detection falls in the
first pass observed after the burn; ``later``; ``missed``) and the surprise (-log10 p) of the first
update after the burn. ``--set TABLE.KEY=VALUE`` changes the scenario as ``cistrack run`` does.
"""
from __future__ import annotations

import argparse
import warnings

import numpy as np
from scipy.optimize import brentq
from scipy.stats import chi2, ncx2

from cistrack import units
from cistrack.least_squares.errors import UnobservableWarning
from cistrack.least_squares.impulse_fit import BurnArc, fit_impulses
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.trajectory import arc_states
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import merge_settings, parse_settings


def lambda_90(alpha: float) -> float:
    c = chi2.isf(alpha, 3)
    return brentq(lambda lam: ncx2.sf(c, 3, lam) - 0.9, 1e-6, 1e4)


def _pass_end(rows, t_b_days: float, passes: int) -> float | None:
    ups = [r for r in rows if r["kind"] == "update" and r["t_days"] > t_b_days]
    seen = sorted({int(r["pass_index"]) for r in ups})[:passes]
    if len(seen) < passes:
        return None
    return max(r["t_days"] for r in ups if int(r["pass_index"]) in seen)


def burn_bound(result, imp, passes: int, alpha: float) -> dict | None:
    ctx, watch = result.context, result.context.maneuvers
    t_b = float(imp.t)
    end = _pass_end(result.rows, float(units.tu_to_days(t_b)), passes)
    start = watch._start_state(t_b - float(units.days_to_tu(1.0)), t_b)
    if end is None or start is None:
        return None
    t = np.asarray(ctx.measurements.times, dtype=float)
    arc = ctx.measurements.subset((t >= start.t) & (t <= float(units.days_to_tu(end)) + 1e-9))
    x = arc_states(ctx.truth_dynamics, ctx.truth.x0, 0.0, np.array([start.t]))[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnobservableWarning)
        fit = fit_impulses(BurnArc(ctx.dynamics, ctx.sensor, arc, FitOptions(area_to_mass="off"),
                                   (start.mean, start.covariance)), x, start.t, [t_b])
    dv = np.asarray(imp.dv) * float(units.vu_to_kms(1.0)) * 1000.0
    u = dv / np.linalg.norm(dv)
    info = float(u @ np.linalg.solve(fit.burns[0].covariance_ms2, u))
    lam = float(np.linalg.norm(dv) ** 2 * info)
    return {"t_days": float(units.tu_to_days(t_b)), "dv_ms": float(np.linalg.norm(dv)),
            "sigma_along_ms": float(1.0 / np.sqrt(info)), "p_detect": float(ncx2.sf(chi2.isf(alpha, 3), 3, lam)),
            "dv90_ms": float(np.sqrt(lambda_90(alpha) / info))}


def detector_outcome(result, imp) -> tuple[str, float]:
    """The run's own detector on this burn: 'next' (first detection in the first pass observed after
    the burn), 'later', or 'missed'; and the surprise (-log10 p) of the first update after the burn."""
    t_b = float(units.tu_to_days(imp.t))
    ups = [r for r in result.rows if r["kind"] == "update" and r["t_days"] > t_b]
    if not ups:
        return "missed", float("nan")
    hits = [r for r in ups if r.get("maneuver_detected") == 1.0]
    first = float(ups[0].get("maneuver_statistic", float("nan")))
    if not hits:
        return "missed", first
    return ("next" if int(hits[0]["pass_index"]) == int(ups[0]["pass_index"]) else "later"), first


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--alpha", type=float, default=1e-4)
    ap.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE",
                    help="a scenario setting, as for cistrack run (e.g. maneuvers.detector.gap_hours=inf)")
    args = ap.parse_args()
    over = merge_settings({"maneuvers": {"response": "none"}}, parse_settings(args.set))
    scen = load_scenario(args.scenario).with_overrides(over)
    print("seed,burn_t_days,dv_ms,sigma_along_ms,p_detect,dv90_ms,detector,first_update_surprise")
    for seed in args.seeds:
        res = run_scenario(scen, seed=seed)
        for imp in res.context.truth_impulses:
            b = burn_bound(res, imp, args.passes, args.alpha)
            if b is not None:
                outcome, first = detector_outcome(res, imp)
                print(f"{seed},{b['t_days']:.3f},{b['dv_ms']:.3f},{b['sigma_along_ms']:.4f},{b['p_detect']:.3f},"
                      f"{b['dv90_ms']:.4f},{outcome},{first:.2f}")


if __name__ == "__main__":
    main()
