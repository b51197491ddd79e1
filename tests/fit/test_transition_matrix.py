"""State transition matrices: the variational equations of the cr3bp and ephemeris plugins agree
with central finite differences of ``propagate``, forward and backward, and the interface's
generic default is exact on linear dynamics."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.interfaces.dynamics import Dynamics
from cistrack.plugin.registry import default_registry

from .arcs import EPOCH, NRHO
from .linear_components import FreeParticle, free_particle_stm


def _central_differences(dyn, x, t0, times, h=1e-6):
    """(K, 6, 6) by central differences, one propagate call per column pair."""
    cols = []
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        p = dyn.propagate(np.stack([x + e, x - e]), t0, times).states
        cols.append((p[:, 0] - p[:, 1]) / (2 * h))
    return np.stack(cols, axis=2)


def _relative_error(a, b):
    return np.max(np.abs(a - b), axis=(1, 2)) / np.max(np.abs(b), axis=(1, 2))


@pytest.mark.parametrize("t0, times", [(0.0, np.array([0.2, 0.7, 1.5])), (1.5, np.array([1.0, 0.3]))],
                         ids=["forward", "backward"])
def test_cr3bp_variational_stm_agrees_with_finite_differences(t0, times):
    dyn = default_registry().create("dynamics", "cr3bp")
    states, stms = dyn.propagate_with_stm(NRHO, t0, times)
    np.testing.assert_allclose(states, dyn.propagate(NRHO[None], t0, times).states[:, 0], rtol=0, atol=1e-10)
    assert _relative_error(stms, _central_differences(dyn, NRHO, t0, times)).max() < 1e-6


@pytest.mark.parametrize("options", [{}, {"j2": True, "srp_area_to_mass_m2_kg": 0.05}], ids=["default", "j2-srp"])
def test_ephemeris_variational_stm_agrees_with_finite_differences(options):
    dyn = default_registry().create("dynamics", "ephemeris", epoch=EPOCH, **options)
    x = dyn.frame.gcrs_to_synodic(dyn.frame.pulsating_to_gcrs(NRHO, 0.0), 0.0)
    times = np.array([0.2, 0.7, 1.2])
    states, stms = dyn.propagate_with_stm(x, 0.0, times)
    np.testing.assert_allclose(states, dyn.propagate(x[None], 0.0, times).states[:, 0], rtol=0, atol=1e-10)
    assert _relative_error(stms, _central_differences(dyn, x, 0.0, times)).max() < 1e-6


def test_interface_default_stm_is_exact_on_linear_dynamics():
    times = np.array([0.5, 1.0, 4.0])
    states, stms = Dynamics.propagate_with_stm(FreeParticle(), np.arange(6.0), 0.0, times)
    for k, t in enumerate(times):
        np.testing.assert_allclose(stms[k], free_particle_stm(t), atol=1e-8)
        np.testing.assert_allclose(states[k], free_particle_stm(t) @ np.arange(6.0), atol=1e-12)


def test_stm_of_a_trajectory_into_the_moon_is_refused_naming_the_moon():
    from cistrack.errors import PropagationError

    dyn = default_registry().create("dynamics", "cr3bp")
    moon = np.array([1.0 - dyn.mu + 0.01, 0.0, 0.0, -0.5, 0.0, 0.0])
    with pytest.raises(PropagationError, match="Moon"):
        dyn.propagate_with_stm(moon, 0.0, np.array([0.5]))
