"""ensemble_arc_states propagates several orbits at once to times on both sides of their epoch:
each orbit's states are those arc_states gives it alone, and an orbit that hits a body is marked."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares.trajectory import arc_states, ensemble_arc_states

from .arcs import cr3bp_arc

TIMES = np.array([-0.3, 0.0, 0.2, 0.2, 0.5, -0.1])  # both sides of t0 = 0, the epoch itself, a repeat


def test_each_orbit_of_the_ensemble_is_the_one_propagated_alone():
    arc = cr3bp_arc()
    states = arc.truth0 + np.array([[0.0] * 6, [1e-4, 0, 0, 0, 1e-4, 0], [0, -2e-4, 1e-4, 0, 0, 0]])
    together, alive = ensemble_arc_states(arc.dynamics, states, 0.0, TIMES)
    assert together.shape == (TIMES.size, 3, 6) and np.all(alive)
    for n, x in enumerate(states):
        np.testing.assert_allclose(together[:, n], arc_states(arc.dynamics, x, 0.0, TIMES), rtol=0, atol=1e-13)


def test_an_orbit_that_hits_a_body_is_marked_and_the_others_kept():
    arc = cr3bp_arc()
    moon = np.array([1.0 - arc.dynamics.mu, 0.0, 0.0])
    falling = np.concatenate([moon + [0.02, 0.0, 0.0], [-1.0, 0.0, 0.0]])  # 7,700 km out, straight at the Moon
    _, alive = ensemble_arc_states(arc.dynamics, np.vstack([arc.truth0, falling]), 0.0, np.array([0.1, 0.3]))
    assert alive.tolist() == [True, False]
