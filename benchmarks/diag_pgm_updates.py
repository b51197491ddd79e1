"""Diagnostic: where does the PGM first make the truth improbable? (issue 16, item 1)

Runs Example 1 (or ``--scenario``) for the given seeds with the default PGM (or with the overrides given) and
prints, for every measurement update, one line with

- prior (the clustered prior the filter is about to update):
  ``prN`` NEES of the truth against the prior mixture's moment-matched Gaussian;
  ``prH`` the truth's HDR level under the prior mixture (estimated from its particles);
  ``M`` clusters and ``nmin`` the smallest; ``kurt`` Mardia's multivariate kurtosis of the
  cluster most responsible for the truth, divided by its Gaussian value d(d+2) = 48 (1 =
  Gaussian; > 1 heavy tails or a bent cluster); ``tcN`` NEES of the truth against that
  component alone;
- reference posterior: the prior particles importance-weighted by the likelihood p(z | x_j)
  (no Gaussian fit, no clustering): ``ess`` its effective sample size and ``isN`` the truth's
  NEES against its weighted mean and covariance (meaningful when ess >~ 100);
- posterior: ``poN`` / ``poH`` NEES and HDR level of the filter's posterior mixture; ``wmax``
  the largest posterior component weight.

Reading: ``prH`` near 1 means propagation + Gaussian fit already lost the truth; fine ``prH`` and
``isN`` with a jump in ``poN`` / ``poH`` mean the update is overconfident.

    python benchmarks/diag_pgm_updates.py --seeds 1030,1035 --iod noisy-range \
        [--set '{"filter": {"n_components": 12}}'] [--only-passes 4,5]
    python benchmarks/diag_pgm_updates.py --scenario example-3 --seeds 5 --only-passes 147

Tuning seeds only (1-60, 1000-1099). Prints the machine it ran on.
"""
from __future__ import annotations

import argparse
import ast
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

from cistrack.plugin.hookspecs import hookimpl  # noqa: E402
from cistrack.evaluation.metrics import nees, step_metrics  # noqa: E402
from cistrack.plugins.filters.measured_components import MeasuredComponents  # noqa: E402
from cistrack.runs.pipeline import run_scenario  # noqa: E402
from cistrack.scenario.loading import load_scenario  # noqa: E402


def mardia_kurtosis_ratio(x: np.ndarray) -> float:
    """Mardia's b_{2,d} of the points x (n, d) divided by its Gaussian expectation d (d + 2)."""
    n, d = x.shape
    c = x - x.mean(axis=0)
    s = (c.T @ c) / n
    y = np.linalg.solve(np.linalg.cholesky(s), c.T)
    return float(np.mean(np.sum(y * y, axis=0) ** 2) / (d * (d + 2)))


def importance_reference(x: np.ndarray, meas: MeasuredComponents) -> tuple[np.ndarray, np.ndarray, float]:
    """Prior particles x (N, 6) weighted by p(z | x): weighted mean (6,), covariance (6, 6), ESS."""
    r = meas.residuals_to_measurement(x)
    li = np.linalg.cholesky(meas.R)
    y = np.linalg.solve(li, r.T)
    logw = -0.5 * np.sum(y * y, axis=0)
    w = np.exp(logw - logw.max())
    w /= w.sum()
    mu = w @ x
    c = x - mu
    return mu, (c * w[:, None]).T @ c, float(1.0 / np.sum(w * w))


class UpdateProbe:
    """Observer of one run: prior diagnostics when the filter predicted to a measurement, the
    posterior ones after the update."""

    def __init__(self):
        self.rows: list[dict] = []
        self._row: dict = {}

    @hookimpl
    def cistrack_step_predicted(self, run, step):
        if step.kind != "update" or step.truth is None:
            return
        flt = run.filter
        truth = np.asarray(step.truth, float)
        mix = step.belief.mixture
        m = step_metrics(step.belief, truth)
        k = int(np.argmax(mix.responsibilities(truth[None])[0]))
        x, labels = flt._x, flt._labels
        counts = np.bincount(labels, minlength=mix.n_components)
        xk = x[labels == k]
        meas = MeasuredComponents(run.sensor, step.measurement)
        mu, cov, ess = importance_reference(x, meas)
        self._row = {"t": step.t * 4.342, "pass": 0, "prN": m["nees"], "prH": m["hdr_level"],
                     "M": mix.n_components, "nmin": int(counts.min()),
                     "kurt": mardia_kurtosis_ratio(xk) if xk.shape[0] > 12 else np.nan,
                     "tcN": nees(truth - mix.means[k], mix.covariances[k]),
                     "ess": ess, "isN": nees(truth - mu, cov) if ess > 7 else np.nan}

    @hookimpl
    def cistrack_step_updated(self, run, step):
        if step.truth is None or not self._row:
            return
        r = self._row
        r.update({"pass": int(step.metrics["pass_index"]), "poN": step.metrics["nees"],
                  "poH": step.metrics["hdr_level"],
                  "wmax": step.diagnostics.get("max_component_weight", np.nan),
                  "custody": step.metrics.get("custody", np.nan), "err": step.metrics["pos_err_km"]})
        self.rows.append(r)
        self._row = {}


_COLS = ("t", "pass", "prN", "prH", "M", "nmin", "kurt", "tcN", "ess", "isN", "poN", "poH", "wmax", "err",
         "custody")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="1030")
    ap.add_argument("--scenario", default="example-1", help="built-in scenario name or TOML file")
    ap.add_argument("--iod", default="", help="IOD name (default: the scenario's own)")
    ap.add_argument("--set", default="{}", help="scenario overrides as a Python dict literal")
    ap.add_argument("--only-passes", default="", help="print only these passes (comma list)")
    ap.add_argument("--summary-only", action="store_true")
    a = ap.parse_args(argv)
    print("\n".join(machine_lines()))
    over = ast.literal_eval(a.set)
    if a.iod:
        over.setdefault("iod", {})["name"] = a.iod
    sc = load_scenario(a.scenario).with_overrides(over)
    passes = {int(p) for p in a.only_passes.split(",") if p}
    for seed in [int(s) for s in a.seeds.split(",")]:
        probe = UpdateProbe()
        t0 = time.perf_counter()
        res = run_scenario(sc, seed=seed, observers=[probe])
        s = res.summary
        print(f"# {a.scenario} seed {seed} {a.iod or sc.components['iod'].name}: custody {'kept' if s.custody_kept else 'LOST'} "
              f"final NEES {s.final['nees']:.1f} err {s.final['pos_err_km']:.1f} km "
              f"({time.perf_counter() - t0:.1f} s)", flush=True)
        if a.summary_only:
            continue
        print(" ".join(f"{c:>7}" for c in _COLS))
        for r in probe.rows:
            if passes and r["pass"] not in passes:
                continue
            print(" ".join(f"{r.get(c, np.nan):7.3g}" for c in _COLS), flush=True)


if __name__ == "__main__":
    main()
