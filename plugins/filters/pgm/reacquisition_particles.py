"""How many particles the PGM draws from a posterior: more while the cloud is reacquiring.

Model. After a long gap the prior cloud is spread over the whole orbit and beyond, its predicted
angles over about 1e5 noise standard deviations. One pass of measurements has to choose between
several hypotheses, the parts of the cloud that the line of sight crosses, and a single
measurement cannot tell them apart. Resampled to ``n_particles``, a hypothesis of a few percent
holds about one minimum-size cluster and is merged into a neighbour or lost to sampling noise
before later measurements can favour it (docs/history/pgm.md has the runs).

The rule. While the prior's predicted measurements at an update spread wider than
``reacquire_spread_sigma`` noise standard deviations, the posterior is resampled with
``reacquire_factor`` x ``n_particles`` particles instead of ``n_particles``. A hypothesis of
weight w then keeps that many times more particles. Once the cloud's predicted spread falls
back under the threshold, the count returns to ``n_particles`` at the next update. The spread is the largest standard deviation of
the predicted-measurement residuals in noise units, sqrt(largest eigenvalue of
R^-1/2 cov(h(x) - z) R^-1/2).

Measurements behind the default factor 4 and threshold 1,000 sigma: docs/history/pgm.md.

Memory. The reacquisition draws are the largest cloud of a run (``reacquire_factor`` x
``n_particles`` particles), so :func:`draw_mixture` makes them in chunks of :data:`DRAW_CHUNK`
rows: the only arrays as long as the draws are the draws themselves (n, d) and their component
labels (n,). It takes the same numbers from the generator, in the same order, as
``GaussianMixture.sample`` (one ``rng.choice`` of the components, then the standard normals row by
row), so the particles are the same.
"""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import GaussianMixture

__all__ = ["DRAW_CHUNK", "draw_mixture", "measurement_spread_sigma", "particles_to_draw"]

DRAW_CHUNK = 65_536  # rows drawn at once by draw_mixture
SPREAD_WHOLE_ROWS = 131_072
"""Up to this many residual rows the spread's whitened residuals (m, N) are held whole (the numbers
Example 1 has always had); above it, summed block by block (16 MB fewer at 1,000,000 particles,
the same spread to rounding)."""


def measurement_spread_sigma(residuals: np.ndarray, R: np.ndarray) -> float:
    """Largest standard deviation of predicted-measurement residuals ``residuals`` (N, m)
    (h(x) - z, angles wrapped) in units of the noise, whose covariance is ``R`` (m, m)."""
    res = np.asarray(residuals, dtype=float)
    if res.shape[0] < 2:
        return 0.0
    L = np.linalg.cholesky(0.5 * (R + R.T))
    mean = res.mean(axis=0)
    if res.shape[0] > SPREAD_WHOLE_ROWS:
        c = _whitened_covariance_in_blocks(res, mean, L)
    else:
        w = np.empty((res.shape[1], res.shape[0]))  # whitened residuals (m, N), centred and whitened
        for a in range(0, res.shape[0], DRAW_CHUNK):  # a chunk at a time (each column is solved on its own)
            w[:, a:a + DRAW_CHUNK] = np.linalg.solve(L, (res[a:a + DRAW_CHUNK] - mean).T)
        c = np.atleast_2d(_covariance_rows(w))
    return float(np.sqrt(max(np.linalg.eigvalsh(c).max(), 0.0)))


def _whitened_covariance_in_blocks(res: np.ndarray, mean: np.ndarray, L: np.ndarray) -> np.ndarray:
    """The covariance (m, m) of the whitened residuals L^-1 (res - mean)^T, summed over blocks of
    :data:`DRAW_CHUNK` rows without holding all N of them (their sum and sum of products)."""
    m, n = res.shape[1], res.shape[0]
    total, products = np.zeros(m), np.zeros((m, m))
    for a in range(0, n, DRAW_CHUNK):
        w = np.linalg.solve(L, (res[a:a + DRAW_CHUNK] - mean).T)
        total += w.sum(axis=1)
        products += w @ w.T
    centre = total / n
    return (products - n * np.outer(centre, centre)) / (n - 1)


def _covariance_rows(w: np.ndarray) -> np.ndarray:
    """``np.cov(w)`` of rows ``w`` (m, N), N >= 2, the same numbers (numpy's centring and product),
    centring ``w`` itself instead of a copy of it. np.cov multiplies ``w`` by a conjugated copy of
    its transpose; the product with the transpose itself sums the same terms in the same order
    (tests/filters/test_pgm_memory.py compares the two) without that copy."""
    w -= w.mean(axis=1)[:, None]
    c = np.dot(w, w.T)
    c *= np.true_divide(1, w.shape[1] - 1)
    return c.squeeze()


def particles_to_draw(spread_sigma: float, n_particles: int, factor: float, threshold_sigma: float) -> int:
    """round(factor x n_particles) while ``spread_sigma`` > ``threshold_sigma``, else
    ``n_particles``; never fewer than ``n_particles`` (a factor of 1 or less is off)."""
    if not spread_sigma > threshold_sigma:
        return n_particles
    return max(n_particles, int(round(factor * n_particles)))


def component_counts(weights: np.ndarray, n: int, rng: np.random.Generator, chunk: int = DRAW_CHUNK) -> np.ndarray:
    """How many of ``n`` draws of ``rng.choice(len(weights), size=n, p=weights)`` fall on each
    component (M,), from the same uniforms in the same order, ``chunk`` of them at a time."""
    p = np.asarray(weights, dtype=np.float64)
    cdf = p.cumsum()  # numpy's choice with p: the normalised cumulative sum, searched on the right
    cdf /= cdf[-1]
    counts = np.zeros(p.size, dtype=np.int64)
    for a in range(0, n, chunk):
        idx = cdf.searchsorted(rng.random(min(chunk, n - a)), side="right")
        counts += np.bincount(idx, minlength=p.size)[:p.size]
    return counts


def draw_mixture(post: GaussianMixture, n: int, rng: np.random.Generator,
                 chunk: int = DRAW_CHUNK) -> tuple[np.ndarray, np.ndarray]:
    """``n`` draws (n, d) from ``post`` and their components (n,) int64, sorted by component: the
    same as ``post.sample(n, rng)``, with no work array longer than ``chunk`` rows."""
    counts = component_counts(post.weights, n, rng, chunk)
    labels = np.repeat(np.arange(post.n_components, dtype=np.int64), counts)
    return post.draw_blocks(np.concatenate(([0], np.cumsum(counts))), rng, chunk), labels
