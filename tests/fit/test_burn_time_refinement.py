"""The burn time is refined to the minimum of the full fits' cost profile
(cistrack.least_squares.impulse_fit.with_time_uncertainty), not one parabola step towards it.

A force-free particle whose position is measured at 0.0-0.2 and 2.0-2.2 (before a burn at 3.0)
and at 3.4-4.0 (after it); the burn's effect is a few sigma per tenth of a time unit, so the
capped cost's profile over the burn time is far from a parabola away from its minimum. Started
at 2.85 with a step of 0.01, one parabola through three points had put the time at 3.11, 2.3 of
its sigmas past the minimum (a survey set of an Earth orbit: 6.9 sigmas short of it, where the
true burn lay). The reference is a dense scan of full fits."""
from __future__ import annotations

import numpy as np

from .linear_components import FreeParticle, PositionSensor, burned_free_particle
from cistrack.least_squares import FitOptions
from cistrack.least_squares.impulse_fit import BurnArc, capped_cost, fit_impulse, fit_impulses, with_time_uncertainty

X0 = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])
DV = np.array([0.0, 5e-5, -2.5e-5])  # VU
TB, EPOCH, GAP = 3.0, 4.0, (2.2, 3.4)
TIMES = np.array([0.0, 0.1, 0.2, 2.0, 2.1, 2.2, 3.4, 3.5, 3.6, 4.0])


def _arc() -> BurnArc:
    sen = PositionSensor()
    truth = np.array([burned_free_particle(X0, DV, TB, t) for t in TIMES])
    return BurnArc(FreeParticle(), sen, sen.simulate(truth, TIMES, np.random.default_rng(1)),
                   FitOptions(reject_outliers=False))


def _cost_at(arc: BurnArc, t: float) -> float:
    return capped_cost(fit_impulses(arc, burned_free_particle(X0, DV, TB, EPOCH), EPOCH, [t]).fit, arc.prior)


def test_a_burn_time_started_off_the_minimum_ends_at_it():
    arc = _arc()
    start = fit_impulse(arc, burned_free_particle(X0, DV, TB, EPOCH), EPOCH, [2.85])
    out = with_time_uncertainty(arc, start, 0.01, bounds=GAP).searched
    grid = np.linspace(2.9, 3.1, 101)
    t_min = grid[int(np.argmin([_cost_at(arc, t) for t in grid]))]
    assert abs(out.t - t_min) < 0.25 * out.t_sigma, (out.t, t_min, out.t_sigma)


def test_the_refined_time_costs_no_more_than_the_start():
    arc = _arc()
    start = fit_impulse(arc, burned_free_particle(X0, DV, TB, EPOCH), EPOCH, [2.85])
    out = with_time_uncertainty(arc, start, 0.01, bounds=GAP)
    assert capped_cost(out.fit, arc.prior) <= capped_cost(start.fit, arc.prior)
