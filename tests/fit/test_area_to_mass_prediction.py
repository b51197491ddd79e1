"""A fit that estimated the area-to-mass ratio is predicted and walked along its line of variations
with the ratio at its estimate: the predicted states are those of a model constructed with it,
and the line's first points raise the chi-square by about sigma^2 (with the ratio left at 0 they
would be far off)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.line_of_variations import line_of_variations
from cistrack.least_squares.prediction import predict_orbit
from cistrack.least_squares.trajectory import arc_states
from cistrack.plugin.registry import default_registry

from .test_area_to_mass_recovery import EPOCH, OFFSET, simulate


@lru_cache(maxsize=1)
def _solved():
    dyn, sensor, ms, x0 = simulate(0.01, 10.0, seed=7)
    return dyn, sensor, ms, fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass="solve"))


def test_prediction_uses_the_estimated_ratio():
    dyn, _, ms, res = _solved()
    value, _ = res.parameter("area_to_mass_m2_kg")
    t = np.array([1.0, 3.0])
    pred = predict_orbit(res, dyn, t, covariance="linear")
    own = default_registry().create("dynamics", "ephemeris", epoch=EPOCH, area_to_mass_m2_kg=value)
    # the prediction integrates the variational equations too (other steps): agreement to 1e-9 LU (0.4 m)
    np.testing.assert_allclose(pred.states, arc_states(own, res.state, res.epoch, t), rtol=0, atol=1e-9)
    assert np.abs(pred.states - arc_states(dyn, res.state, res.epoch, t)).max() > 1e-6


def test_the_line_of_variations_holds_the_ratio_at_its_estimate():
    dyn, sensor, ms, res = _solved()
    pts = line_of_variations(dyn, sensor, ms, res, step=0.5, max_sigma=0.5, max_delta_chi2=float("inf"))
    assert len(pts) == 3
    rise = np.array([p.chi2 - res.chi2 for p in pts if p.sigma != 0.0])
    assert np.all(np.abs(rise - 0.25) < 0.25), rise
