"""Fixtures shared by the sensor and reader tests: the default observer and a short NRHO truth
arc (imported by their conftest files)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.plugins.sensors.ground_telescope import GroundTelescope

from reference_cr3bp import cr3bp_rhs  # tests/ is on sys.path


@pytest.fixture(scope="session")
def telescope() -> GroundTelescope:
    return GroundTelescope()


@pytest.fixture(scope="session")
def nrho_arc():
    """Approximate 9:2 NRHO sampled every ~10 minutes for 5 days: times (K,) TU, states (K, 6)."""
    x0 = [1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0]
    t_end = 5 * 86400.0 / 375149.0
    times = np.arange(0.0, t_end, 600.0 / 375149.0)
    sol = solve_ivp(cr3bp_rhs, (0.0, t_end), x0, t_eval=times, rtol=1e-11, atol=1e-12, method="DOP853")
    return times, sol.y.T.copy()
