"""Static scene geometry: libration points, primaries, covariance ellipsoids, subsampling."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cistrack.errors import ParameterError
from cistrack.plugins.recorders.rerun_recorder import subsample_indices
from cistrack.plugins.recorders.scene import (
    EARTH_MOON_MU, libration_points, position_ellipsoids, primary_positions, rotation_quaternions,
    system_mu,
)
from cistrack.units import LU_KM


def test_collinear_points_match_the_reference_values_for_the_earth_moon_mu():
    lp = libration_points(EARTH_MOON_MU)
    np.testing.assert_allclose(lp[:2, 0], [0.8369151, 1.1556822], atol=5e-8)


@pytest.mark.parametrize("mu", [EARTH_MOON_MU, 3.0e-6, 0.1, 0.3])
def test_libration_points_are_equilibria_of_the_cr3bp_dynamics(registry, mu):
    dyn = registry.create("dynamics", "cr3bp", mu=mu)
    states = np.hstack([libration_points(mu), np.zeros((5, 3))])
    acc = dyn.derivatives(0.0, states)[:, 3:]
    np.testing.assert_allclose(acc, 0.0, atol=1e-11)


def test_libration_points_reject_an_impossible_mass_ratio():
    with pytest.raises(ParameterError, match="mu"):
        libration_points(0.7)


def test_primaries_sit_at_minus_mu_and_one_minus_mu():
    np.testing.assert_array_equal(primary_positions(0.2), [[-0.2, 0, 0], [0.8, 0, 0]])


def test_system_mu_is_read_from_the_dynamics(registry):
    assert system_mu(registry.create("dynamics", "cr3bp", mu=0.05)) == 0.05


def test_quaternions_reproduce_random_rotations():
    rot = Rotation.random(200, random_state=1).as_matrix()
    q = rotation_quaternions(rot)
    np.testing.assert_allclose(Rotation.from_quat(q).as_matrix(), rot, atol=1e-12)


def test_ellipsoid_surface_is_at_n_sigma_mahalanobis_distance(rng):
    a = rng.standard_normal((4, 6, 6))
    cov = a @ np.swapaxes(a, 1, 2) * 1e-8 + np.eye(6) * 1e-12
    means = rng.standard_normal((4, 6))
    centers, half, quat = position_ellipsoids(means, cov, n_sigma=2.5)
    np.testing.assert_allclose(centers, means[:, :3] * LU_KM)
    u = rng.standard_normal((100, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    for i in range(4):
        x = Rotation.from_quat(quat[i]).apply(u * half[i])
        p = cov[i, :3, :3] * LU_KM**2
        maha = np.sqrt(np.einsum("ni,ij,nj->n", x, np.linalg.inv(p), x))
        np.testing.assert_allclose(maha, 2.5, rtol=1e-9)


def test_subsample_is_deterministic_sorted_and_distinct():
    a = subsample_indices(10_000, 500, seed=4)
    b = subsample_indices(10_000, 500, seed=4)
    np.testing.assert_array_equal(a, b)
    assert np.all(np.diff(a) > 0) and a[0] >= 0 and a[-1] < 10_000


def test_subsample_keeps_everything_when_under_the_cap():
    assert subsample_indices(100, 100) is None


def test_most_likely_component_agrees_with_the_mixture_responsibilities(rng):
    from cistrack.model.belief import GaussianMixture
    from cistrack.plugins.recorders.scene import most_likely_component

    a = rng.standard_normal((4, 6, 6))
    mix = GaussianMixture(rng.dirichlet(np.ones(4)), rng.standard_normal((4, 6)),
                          a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(6))
    x, _ = mix.sample(2000, rng)
    np.testing.assert_array_equal(most_likely_component(x, mix), np.argmax(mix.responsibilities(x), axis=1))
