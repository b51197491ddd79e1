"""How often would a perfectly calibrated filter lose custody under cistrack's custody rule?

    python benchmarks/custody_ceiling.py [SCENARIO] [--first-seed N] [--n-seeds K] [--realizations M]

A reference for the custody counts of docs/calibration.md. The rule (core/evaluation/custody.py) declares
custody lost when the truth lies outside the 0.997 highest-density region on 2 consecutive
updates, or its log-density falls below -100. A filter whose belief is the exact posterior still
sees its truth there now and then; how often depends on how long an unlucky error persists from
one update to the next, which is a matter of geometry and schedule.

The surrogate. For each seed the scenario is prepared as a run would be (truth, schedule,
measurements, IOD cloud). Around the truth the problem is linearised: the state transition
between consecutive updates by central differences of the scenario's own dynamics, the azimuth /
elevation Jacobian by central differences of its sensor, the prior covariance is the IOD cloud's.
On that linear-Gaussian problem the Kalman filter is the exact posterior, so its posterior
covariances P_k are computed once and the errors e_k = x_k - m_k are sampled directly
(``--realizations`` draws of the initial error and of every measurement noise):
e_k = (I - K_k H_k) Phi_k e_(k-1) - K_k v_k. At each update the truth's HDR level is the
chi-square(6) CDF of e_k^T P_k^-1 e_k and its log-density the Gaussian's in km and km/s; the
rule above is applied to each realization. The share of realizations that lose custody is the
loss rate of an exactly calibrated filter on that geometry. The real problem is nonlinear, so
this is a reference, not a bound. Self-check printed with it: the mean posterior NEES over the
realizations, which is 6 at every update for an exact filter.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.stats import chi2

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack import units  # noqa: E402
from cistrack.evaluation.custody import CustodyRule  # noqa: E402
from cistrack.runs.pipeline import prepare_run  # noqa: E402
from cistrack.scenario.loading import load_scenario  # noqa: E402

_STEP_STATE = np.array([1e-7] * 3 + [1e-7] * 3)  # central-difference steps (LU, VU)


def _transition(dynamics, x: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """Phi (6, 6) of the flow from t0 to t1 around x, by central differences."""
    pert = np.concatenate([x + np.diag(_STEP_STATE), x - np.diag(_STEP_STATE)])
    end = dynamics.propagate(pert, t0, np.array([t1])).final
    return ((end[:6] - end[6:]) / (2.0 * _STEP_STATE)).T


def _jacobian(sensor, cols: np.ndarray, x: np.ndarray, t: float) -> np.ndarray:
    """H (m, 6) of the measured columns around x, by central differences (angles unwrapped)."""
    pert = np.concatenate([x + np.diag(_STEP_STATE), x - np.diag(_STEP_STATE)])
    z = np.asarray(sensor.measure(pert, t), dtype=float)[:, cols]
    dz = z[:6] - z[6:]
    dz = (dz + np.pi) % (2.0 * np.pi) - np.pi
    return (dz / (2.0 * _STEP_STATE[:, None])).T


def linearised_problem(scenario, seed: int):
    """(P0 (6, 6), [Phi_k (6, 6)], [H_k (m, 6)], [R_k (m, m)]) for the updates of one run."""
    ctx, _ = prepare_run(scenario, seed)
    cloud = ctx.iod_cloud
    P0 = np.cov(cloud.states.T, aweights=cloud.weights)
    t_prev, x_prev = float(cloud.epoch), ctx.truth_at(float(cloud.epoch))
    names = list(ctx.sensor.names)
    phis, hs, rs = [], [], []
    for i in range(len(ctx.measurements)):
        m = ctx.measurements[i]
        if m.t <= cloud.epoch + 1e-12:
            continue
        m = m.angles_only() if "range" in m.names else m
        cols = np.array([names.index(n) for n in m.names])
        x = ctx.truth_at(float(m.t))
        phis.append(_transition(ctx.dynamics, x_prev, t_prev, float(m.t)))
        hs.append(_jacobian(ctx.sensor, cols, x, float(m.t)))
        rs.append(np.asarray(m.covariance, dtype=float))
        t_prev, x_prev = float(m.t), x
    return P0, phis, hs, rs


def calibrated_losses(P0, phis, hs, rs, realizations: int, rng: np.random.Generator,
                      rule: CustodyRule = CustodyRule()) -> tuple[np.ndarray, np.ndarray]:
    """Simulate the exact Kalman filter's errors; returns (lost (M,) bool, mean NEES per update (K,))."""
    scale = np.array([units.LU_KM] * 3 + [units.VU_KMS] * 3)  # LU, VU -> km, km/s
    e = rng.multivariate_normal(np.zeros(6), P0, size=realizations)
    P = P0.copy()
    run = np.zeros(realizations, dtype=int)
    lost = np.zeros(realizations, dtype=bool)
    mean_nees = []
    for phi, H, R in zip(phis, hs, rs):
        P = phi @ P @ phi.T
        e = e @ phi.T
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        v = rng.multivariate_normal(np.zeros(R.shape[0]), R, size=realizations)
        e = e - e @ (K @ H).T - v @ K.T
        I_KH = np.eye(6) - K @ H
        P = I_KH @ P @ I_KH.T + K @ R @ K.T  # Joseph form
        nees = np.einsum("ni,ij,nj->n", e, np.linalg.inv(P), e)
        mean_nees.append(float(nees.mean()))
        P_km = P * np.outer(scale, scale)
        loglik = -0.5 * nees - 0.5 * np.linalg.slogdet(2.0 * np.pi * P_km)[1]
        run = np.where(chi2.cdf(nees, 6) > rule.hdr_threshold, run + 1, 0)
        lost |= (run >= rule.hdr_consecutive) | (loglik < rule.loglik_threshold)
    return lost, np.array(mean_nees)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="example-1")
    ap.add_argument("--first-seed", type=int, default=9000)
    ap.add_argument("--n-seeds", type=int, default=5)
    ap.add_argument("--realizations", type=int, default=100_000)
    args = ap.parse_args(argv)
    for line in machine_lines():
        print(line)
    scenario = load_scenario(args.scenario)
    print(f"\nscenario {args.scenario}: custody lost by an exact (linearised) filter, "
          f"{args.realizations} realizations per seed\n")
    print("| seed | updates | custody lost | mean posterior NEES (exact: 6) min-max |")
    print("|---|---|---|---|")
    rates = []
    for seed in range(args.first_seed, args.first_seed + args.n_seeds):
        P0, phis, hs, rs = linearised_problem(scenario, seed)
        lost, nees = calibrated_losses(P0, phis, hs, rs, args.realizations, np.random.default_rng(seed))
        rates.append(lost.mean())
        print(f"| {seed} | {len(phis)} | {100 * lost.mean():.2f} % | {nees.min():.2f}-{nees.max():.2f} |")
    print(f"\nmean over seeds: {100 * np.mean(rates):.2f} % lost, i.e. custody kept in "
          f"{100 * (1 - np.mean(rates)):.1f} of 100 runs by a perfectly calibrated filter")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
