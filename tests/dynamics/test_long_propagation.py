"""Long propagation through a 150-day shutoff (the paper's Example 3), run with -m slow."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP


@pytest.mark.slow
def test_150_day_propagation_of_a_dispersed_nrho_cloud_stays_finite_and_conserves_jacobi(rng):
    orbit = ORBITS["nrho-3-1"]
    sig = np.r_[[units.km_to_lu(1000.0)] * 3, [units.kms_to_vu(2e-2)] * 3]   # some hit the Moon
    states = orbit.state + rng.normal(size=(2000, 6)) * sig
    dyn = CR3BP()
    times = np.linspace(0.0, float(units.days_to_tu(150.0)), 16)[1:]
    prop = dyn.propagate(states, 0.0, times)
    assert np.all(np.isfinite(prop.states))
    counts = prop.impact_counts(dyn.bodies)
    assert sum(counts.values()) == int(np.sum(~prop.alive))
    alive = prop.alive
    drift = np.abs(dyn.jacobi(prop.final[alive]) - dyn.jacobi(states[alive]))
    assert np.median(drift) <= 1e-9
    # impacted particles sit on the surface of the body they hit
    for b, body in enumerate(dyn.bodies):
        hit = prop.impact_body == b
        if np.any(hit):
            r = np.linalg.norm(prop.final[hit, :3] - body.position, axis=1)
            np.testing.assert_allclose(r, body.radius, rtol=1e-9)
