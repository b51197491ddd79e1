"""The grid on which closest approaches are first looked for (events._coarse_track) comes from one
dense integration evaluated at every grid time together: the same states as propagating to each
grid time (to the integrator's tolerance), the same search windows, and frozen at an impact."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.least_squares.events import APPROACH_STEP_MINUTES, _approach_windows, _coarse_track, first_impact

from cistrack.plugin.registry import default_registry

from .test_orbit_events import _towards_moon as _near_moon

STEP = APPROACH_STEP_MINUTES * 60.0 / units.TU_S


@pytest.fixture(scope="module")
def dyn():
    return default_registry().create("dynamics", "ephemeris", epoch="2026-03-01T00:00:00Z")


def _propagated(dyn, x, grid):
    """The grid states (K, 1, 6) from propagating to each grid time."""
    return np.concatenate([x[None, None], dyn.propagate(x[None], 0.0, grid[1:]).states])


def test_the_dense_grid_matches_propagating_to_each_time_and_finds_the_same_windows(dyn):
    x = _near_moon(dyn, np.array([20000.0, 0.0, 0.0]), np.array([-1.0, 0.25, 0.1]))
    grid, states, impact = _coarse_track(dyn, x, 0.0, float(units.days_to_tu(3.0)), STEP)
    want = _propagated(dyn, x, grid)
    assert impact == np.inf and np.array_equal(states[0, 0], x)
    err_km = np.abs(states - want)[..., :3].max() * units.LU_KM
    assert err_km < 1e-3, err_km
    for body in ("Moon", "Earth"):
        assert _approach_windows(dyn, (grid, states, impact), body) == \
            _approach_windows(dyn, (grid, want, impact), body)
    assert len(_approach_windows(dyn, (grid, states, impact), "Moon")) == 1


def test_after_an_impact_the_grid_holds_the_impact_point(dyn):
    off = np.array([20000.0, 5000.0, 3000.0])
    x = _near_moon(dyn, off, -off / np.linalg.norm(off) + np.array([0.0, 0.05, 0.0]))
    t_hit, body = first_impact(dyn, x, 0.0, float(units.days_to_tu(2.0)))
    grid, states, impact = _coarse_track(dyn, x, 0.0, float(units.days_to_tu(2.0)), STEP)
    assert body == "Moon" and impact == pytest.approx(t_hit, abs=1e-12)
    after = grid > impact
    assert after.any() and np.all(states[after, 0] == states[np.argmax(after), 0])
    moon = dyn.frame.moon_synodic(np.array([impact]))[0]
    assert abs(np.linalg.norm(states[after][0, 0, :3] - moon) * units.LU_KM - 1737.4) < 1.0
