"""The CompiledDynamics machinery as a third party uses it: a new model from its rhs alone."""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from cistrack.propagation import CompiledDynamics


@njit(cache=True)
def oscillator_rhs(t, y, p, out):
    """Three uncoupled harmonic oscillators with angular frequency p[0]."""
    w2 = p[0] * p[0]
    for i in range(3):
        out[i] = y[3 + i]
        out[3 + i] = -w2 * y[i]


class Oscillator(CompiledDynamics):
    rhs = oscillator_rhs

    def __init__(self, omega: float = 2.0, rtol: float = 1e-12, atol: float = 1e-14):
        self.omega = omega
        self.rtol = rtol
        self.atol = atol

    def params_vector(self):
        return np.array([self.omega])


def test_a_new_model_defined_by_its_rhs_propagates_to_the_closed_form(rng):
    dyn = Oscillator()
    states = rng.normal(size=(50, 6))
    times = np.linspace(0.5, 10.0, 5)
    prop = dyn.propagate(states, 0.0, times)
    w = dyn.omega
    for k, t in enumerate(times):
        x = states[:, :3] * np.cos(w * t) + states[:, 3:] / w * np.sin(w * t)
        v = -states[:, :3] * w * np.sin(w * t) + states[:, 3:] * np.cos(w * t)
        np.testing.assert_allclose(prop.states[k], np.c_[x, v], atol=1e-9)
    assert prop.alive.all() and (prop.impact_body == -1).all()


@pytest.mark.slow  # compiles its own kernel in memory (~20 s on 2 cores)
def test_a_model_defined_in_a_function_still_works_without_cache():
    @njit
    def decay(t, y, p, out):
        for i in range(6):
            out[i] = -p[0] * y[i]

    class Decay(CompiledDynamics):
        rhs = decay

        def __init__(self, rtol: float = 1e-12, atol: float = 1e-14):
            self.rtol = rtol
            self.atol = atol

        def params_vector(self):
            return np.array([0.5])

    out = Decay().propagate(np.ones((3, 6)), 0.0, 2.0).final
    np.testing.assert_allclose(out, np.exp(-1.0), rtol=1e-10)


def test_derivatives_of_a_new_model():
    d = Oscillator(omega=3.0).derivatives(0.0, np.array([[1.0, 0, 0, 0, 2.0, 0]]))
    np.testing.assert_allclose(d, [[0, 2.0, 0, -9.0, 0, 0]])


def test_empty_ensemble_propagates_to_an_empty_result():
    prop = Oscillator().propagate(np.zeros((0, 6)), 0.0, [1.0, 2.0])
    assert prop.states.shape == (2, 0, 6)
