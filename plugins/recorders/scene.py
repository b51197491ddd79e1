"""Static geometry of the Earth–Moon synodic scene and covariance ellipsoids, in km.

Everything here is plain numpy: the rerun recorder turns these arrays into archetypes.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import ParameterError
from cistrack.astro.primaries import EARTH_RADIUS_KM, MOON_RADIUS_KM, mass_ratio
from cistrack.astro.primaries import MU_EARTH_MOON as EARTH_MOON_MU
from cistrack.units import LU_KM

__all__ = [
    "EARTH_MOON_MU", "EARTH_RADIUS_KM", "MOON_RADIUS_KM", "LIBRATION_NAMES",
    "libration_points", "primary_positions", "system_mu", "position_ellipsoids",
    "rotation_quaternions", "most_likely_component",
]

LIBRATION_NAMES: tuple[str, ...] = ("L1", "L2", "L3", "L4", "L5")


def _collinear_gradient(x: float, mu: float) -> float:
    """dU/dx of the CR3BP effective potential on the x axis (y = z = 0)."""
    r1 = x + mu
    r2 = x - 1.0 + mu
    return x - (1.0 - mu) * r1 / abs(r1) ** 3 - mu * r2 / abs(r2) ** 3


def libration_points(mu: float = EARTH_MOON_MU) -> np.ndarray:
    """The five libration points of the CR3BP with mass ratio ``mu``.

    Returns
    -------
    (5, 3) float
        L1..L5 in the synodic frame, LU. The collinear points are the roots of dU/dx on the x
        axis, bracketed between and outside the primaries and solved to 1e-14 LU; L4/L5 are the
        equilateral points (0.5 - mu, ±sqrt(3)/2, 0).
    """
    mu = float(mu)
    if not (0.0 < mu < 0.5):
        raise ParameterError(f"libration points: mass ratio mu = {mu!r} must lie in (0, 0.5)")
    moon = 1.0 - mu
    earth = -mu
    eps = 1e-9
    f = lambda x: _collinear_gradient(x, mu)  # noqa: E731
    # dU/dx goes from -inf (just outside Earth) to +inf (just inside the Moon) with one root
    # between the primaries (L1); likewise beyond the Moon (L2) and beyond the Earth (L3).
    from scipy.optimize import brentq  # on use: slow to import

    l1 = brentq(f, earth + eps, moon - eps, xtol=1e-14, maxiter=500)
    l2 = brentq(f, moon + eps, 2.0, xtol=1e-14, maxiter=200)
    l3 = brentq(f, -2.0, earth - eps, xtol=1e-14, maxiter=200)
    h = np.sqrt(3.0) / 2.0
    return np.array([[l1, 0.0, 0.0], [l2, 0.0, 0.0], [l3, 0.0, 0.0],
                     [0.5 - mu, h, 0.0], [0.5 - mu, -h, 0.0]])


def primary_positions(mu: float = EARTH_MOON_MU) -> np.ndarray:
    """Earth and Moon positions (2, 3), LU: (-mu, 0, 0) and (1 - mu, 0, 0)."""
    return np.array([[-mu, 0.0, 0.0], [1.0 - mu, 0.0, 0.0]])


def system_mu(dynamics) -> float:
    """The mass ratio of ``dynamics``: the Moon's mass fraction among its primaries, else the
    Earth–Moon value (:func:`cistrack.astro.primaries.mass_ratio`)."""
    return mass_ratio(dynamics)


def rotation_quaternions(rot: np.ndarray) -> np.ndarray:
    """Unit quaternions (M, 4) in (x, y, z, w) order of proper rotation matrices ``rot`` (M, 3, 3).

    Uses the largest-diagonal branch per matrix so that it is stable for every rotation.
    """
    r = np.asarray(rot, dtype=float)
    m = r.shape[0]
    q = np.empty((m, 4))
    tr = np.trace(r, axis1=1, axis2=2)
    diag = np.diagonal(r, axis1=1, axis2=2)
    branch = np.where(tr > diag.max(axis=1), 3, diag.argmax(axis=1))
    # w largest
    s = branch == 3
    if s.any():
        t = np.sqrt(np.maximum(tr[s] + 1.0, 0.0)) * 2.0
        q[s, 3] = 0.25 * t
        q[s, 0] = (r[s, 2, 1] - r[s, 1, 2]) / t
        q[s, 1] = (r[s, 0, 2] - r[s, 2, 0]) / t
        q[s, 2] = (r[s, 1, 0] - r[s, 0, 1]) / t
    for i in range(3):  # three branches, each vectorised over the matrices that take it
        s = branch == i
        if not s.any():
            continue
        j, k = (i + 1) % 3, (i + 2) % 3
        t = np.sqrt(np.maximum(1.0 + r[s, i, i] - r[s, j, j] - r[s, k, k], 0.0)) * 2.0
        q[s, i] = 0.25 * t
        q[s, 3] = (r[s, k, j] - r[s, j, k]) / t
        q[s, j] = (r[s, j, i] + r[s, i, j]) / t
        q[s, k] = (r[s, k, i] + r[s, i, k]) / t
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def position_ellipsoids(means: np.ndarray, covariances: np.ndarray,
                        n_sigma: float = 3.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n-sigma position ellipsoids of mixture components, in km.

    Parameters
    ----------
    means : (M, >=3) float, LU (only the position part is used)
    covariances : (M, >=3, >=3) float, LU² (only the position block is used)
    n_sigma : float, the ellipsoid's Mahalanobis radius

    Returns
    -------
    centers_km : (M, 3), half_sizes_km : (M, 3), quaternions : (M, 4) in (x, y, z, w) order
        The ellipsoid of component i is {centers_i + R_i diag(half_sizes_i) u : |u| = 1}, with
        R_i the rotation of ``quaternions[i]`` and half_sizes the n-sigma semi-axes.
    """
    mu = np.asarray(means, dtype=float)[:, :3]
    p = np.asarray(covariances, dtype=float)[:, :3, :3]
    p = 0.5 * (p + np.swapaxes(p, 1, 2))
    w, v = np.linalg.eigh(p)
    w = np.maximum(w, 0.0)
    det = np.linalg.det(v)
    v[:, :, 2] *= np.where(det < 0, -1.0, 1.0)[:, None]  # make every eigenbasis a proper rotation
    half = n_sigma * np.sqrt(w) * LU_KM
    return mu * LU_KM, half, rotation_quaternions(v)


def most_likely_component(points: np.ndarray, mixture) -> np.ndarray:
    """Index of the component with the largest posterior probability for each point.

    Parameters
    ----------
    points : (N, d) float, in the mixture's units
    mixture : cistrack.model.belief.GaussianMixture of dimension d

    Returns
    -------
    (N,) int
        argmax_i of w_i N(x; mu_i, P_i), one (N, d) x (d, d) product per component (used to
        colour particles whose filter gave no labels).
    """
    from scipy.linalg import solve_triangular  # on use: slow to import

    x = np.asarray(points, dtype=float)
    chol = mixture.cholesky()
    best = np.full(x.shape[0], -np.inf)
    label = np.zeros(x.shape[0], dtype=np.int64)
    with np.errstate(divide="ignore"):
        logw = np.log(mixture.weights)
    for i in range(mixture.n_components):  # few components; vectorised over points
        linv = solve_triangular(chol[i], np.eye(chol.shape[1]), lower=True, check_finite=False)
        z = (x - mixture.means[i]) @ linv.T
        score = logw[i] - 0.5 * np.einsum("ij,ij->i", z, z) - np.sum(np.log(np.diagonal(chol[i])))
        better = score > best
        best[better] = score[better]
        label[better] = i
    return label
