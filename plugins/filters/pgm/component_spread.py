"""Moment-preserving shrinkage of clustered components toward their common mean.

A hard partition (k-means cells) of a cloud gives components that are truncated pieces of it:
each piece's covariance lacks the spread along the directions that separate it from its
neighbours. Conditioned on a measurement oblique to those directions, a piece then claims a
conditional covariance smaller than the cloud's (for a Gaussian cut into cells, the piece's
conditional variance grows with its length along the cut, so a shorter piece is narrower),
and repeated updates compound it: on a linear-Gaussian problem (6-D, one coordinate measured
15 times, 8 seeds) a 6-component PGM ended with mean NEES 16.7 against 7.1 for the exact
Kalman filter, while one component matched it (7.0).

The shrinkage (as in Liu and West's kernel shrinkage for particle filters) moves each mean
toward the mixture mean and gives the lost spread back to every component:

    mu_i' = mu + lam (mu_i - mu),   P_i' = P_i + (1 - lam^2) B,   B = sum_i w_i (mu_i - mu)(mu_i - mu)^T

which keeps the mixture's mean and covariance exactly (sum w_i P_i' + lam^2 B = W + B). lam = 1
is the plain partition, lam = 0 a single Gaussian (the UKF's belief).

Not while reacquiring. The model above is one cloud cut into cells. After a long gap the cloud is
several hypotheses, the parts of a long arc that the line of sight may cross, spread over about
1e5 noise sigmas of predicted measurement (reacquisition_particles.py). Shrinking them pulls every
hypothesis toward their common mean, in the empty space between them, and the inflated
components reach across several line-of-sight crossings at once. The PGM therefore shrinks only
while the prior's predicted measurements spread over at most ``shrink_spread_sigma`` noise
sigmas (default 1,000, the reacquisition threshold: the same regime).
Measured (custody kept / runs; Example 2 = slow L2 transit with a 10-day gap, Example 3 = 3:1
NRHO with a 150-day gap; `cistrack study run`, seen seeds):

| PGM | Example 3, seeds 1-20 | Example 3, 3000-3029 | Example 2, 1-10 | Example 2, 3000-3029 |
|---|---|---|---|---|
| no shrinkage (kept_spread 1.0) | 16/20 | 23/30 (earlier main) | 9/10 | 18/30 (earlier main) |
| kept_spread 0.7 at every update | 8/20 (7 diverged) | 9/30 (earlier main) | | |
| kept_spread 0.7, not while reacquiring | 17/20 | 27/30 | 10/10 | 29/30 |

Held out, run once after the choice (seeds 3200-3229, scenarios as then shipped): Example 2
30/30; Example 3 24/30 with 10,000 particles (4 lost in the first updates after the gap, 2
diverged). Example 3 now carries 20,000 particles (example-3.toml; 84/90 against 79/90 on seen
seeds), not checked on held-out seeds. Example 3 stays short of 90%: its remaining losses pick
the wrong hypothesis while reacquiring.

Without shrinkage the late Example 3 losses are the drift to overconfidence within the pass after
the gap (truth NEES 10 -> 1e3 -> 1e7 over 17 updates), and most Example 2 losses begin in its
33-hour first pass, the same drift as Example 1's; shrinking at every update instead ends
~280,000 km away on the wrong hypothesis. Shrinking within groups of overlapping components
(linked when their means lie within 3 sigma under P_i + P_j) was tried too: 18/20 and 17/30 on
Example 3, because the reacquiring components are so wide that they all overlap.

The price is precision. Shrinkage moves each component toward the moment-matched Gaussian, which
for a curved (non-Gaussian) cloud discards real structure, not only the cells' truncation. On the
runs that both configurations keep, Example 3 ends with position sigma median 125 km against
21 km without shrinkage (error median 67 against 14 km; NEES median 3.4 and 4.6: both
consistent), so most Example 3 runs end "not-converged" (sigma above 100 km) rather than
"tracking"; Example 2 with 51 against 13 km (error 30 against 9 km). kept_spread 0.85 kept
17/20 of Example 3's seeds 1-20 with error median 50 km: no better custody, half the precision
cost. Example 1 hardly notices the rule (it skips the shrinkage on 0-3 updates per run, the first
after the IOD and of pass 2): seeds 1000-1023, 24/24 kept with either IOD before and after, final
NEES 90th percentile 7.3 / 7.3 before and 6.9 / 7.2 after (noisy / uniform range).
"""
from __future__ import annotations

import numpy as np

__all__ = ["shrink_components"]


def shrink_components(weights: np.ndarray, means: np.ndarray, covs: np.ndarray,
                      kept_spread: float) -> tuple[np.ndarray, np.ndarray]:
    """Shrink components (weights (M,), means (M, d), covs (M, d, d)) toward their mixture mean,
    keeping ``kept_spread`` = lam^2 in [0, 1] of the between-component covariance as spread of
    the means and adding the rest to every covariance. Returns (means (M, d), covs (M, d, d))."""
    w = np.asarray(weights, dtype=float)
    w = w / w.sum()
    mu = w @ means
    dm = means - mu
    B = (dm * w[:, None]).T @ dm
    lam = np.sqrt(kept_spread)
    return mu + lam * dm, covs + (1.0 - kept_spread) * B[None]
