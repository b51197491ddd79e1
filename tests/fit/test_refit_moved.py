"""A burn fit moved in time starts from its estimate: state, delta-v, rejected observations and the
area-to-mass ratio (cistrack.least_squares.impulse_fit.refit_moved), on the three-site NRHO
campaign with a 0.3 m/s burn (burn_campaigns.burned) fitted with the ratio solved for."""
from __future__ import annotations

import numpy as np
import pytest

from .burn_campaigns import burned, truth_state
from cistrack.least_squares.impulse_fit import BurnArc, capped_cost, fit_impulses, fit_moved, refit_moved
from cistrack.least_squares.options import FitOptions


@pytest.fixture(scope="module")
def estimate():
    b = burned(0.3)
    arc = BurnArc(b.dynamics, b.sensor, b.measurements, FitOptions(area_to_mass="solve"))
    t0 = float(b.measurements.times[-1])
    return b, arc, fit_impulses(arc, truth_state(b, t0), t0, [b.t_burn])


def test_a_refit_at_the_estimates_own_time_is_the_estimate_at_once(estimate):
    b, arc, est = estimate
    again = refit_moved(arc, est.fit, est.burns, 0, b.t_burn)
    assert again.fit.iterations <= 2
    assert abs(capped_cost(again.fit) - capped_cost(est.fit)) < 1e-6
    assert np.allclose(again.fit.parameters, est.fit.parameters, rtol=0.0, atol=1e-6)


def test_the_area_to_mass_ratio_starts_from_the_estimate_not_the_model(estimate):
    """From the model's own ratio (fit_moved alone) the same refit needs more iterations."""
    b, arc, est = estimate
    assert est.fit.parameter_names[-1] == "area_to_mass_m2_kg" and est.fit.parameters[-1] != 0.0
    again = refit_moved(arc, est.fit, est.burns, 0, b.t_burn)
    plain = fit_moved(arc, est.fit.state, est.fit.epoch, est.burns, 0, b.t_burn)
    assert again.fit.iterations < plain.fit.iterations
