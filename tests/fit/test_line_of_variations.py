"""The line of variations (cistrack.least_squares.line_of_variations): points of least squares along the
weakest direction of a fit, each on its hyperplane v^T N (x - x*) = sigma.

Checked against quantities computed independently of the module: the chi-square of a state from
the dynamics' ``propagate`` and the sensor's ``measure`` directly, the constraint from the fit's
own covariance, and, on a long arc where the problem is nearly linear, the closed form of the
linear case (points x* + sigma v, chi-square chi2* + sigma^2)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.errors import UnobservableWarning
from cistrack.least_squares.line_of_variations import line_of_variations, line_summary, line_weights, sample_line, weakest_direction
from cistrack.model.measurement import MeasurementSet

from .arcs import GUESS_OFFSET, cr3bp_arc

OPTS = FitOptions(reject_outliers=False)


def _chi2(arc, ms: MeasurementSet, x: np.ndarray) -> float:
    """Chi-square of the state x at t = 0 over the arc, from propagate and measure alone."""
    states = arc.dynamics.propagate(x[None], 0.0, ms.times).states[:, 0]
    d = ms.values - arc.sensor.measure(states, ms.times)
    d[:, 0] = (d[:, 0] + np.pi) % (2 * np.pi) - np.pi  # azimuth wraps
    return float(np.sum((d / ms.sigmas) ** 2))


def _one_night(ms: MeasurementSet) -> MeasurementSet:
    keep = ms.times < ms.times[0] + 0.15  # ~15 hours: the first pass only
    return MeasurementSet(ms.times[keep], ms.values[keep], ms.sigmas[keep], ms.names)


@lru_cache(maxsize=None)
def _fit_and_line(nights: str, seed: int):
    arc = cr3bp_arc()
    ms = arc.noisy(seed)
    if nights == "one":  # one night leaves a direction nearly unobservable: the fit says so
        ms = _one_night(ms)
        with pytest.warns(UnobservableWarning, match="nearly unobservable"):
            fit = fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0, options=OPTS)
    else:
        fit = fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0, options=OPTS)
    assert fit.converged
    return arc, ms, fit, line_of_variations(arc.dynamics, arc.sensor, ms, fit, step=1.0, max_sigma=3.0,
                                            options=OPTS)


def test_the_weakest_direction_is_one_sigma_long():
    _, _, fit, _ = _fit_and_line("all", 1)
    v = weakest_direction(fit.covariance)
    assert v @ np.linalg.solve(fit.covariance, v) == pytest.approx(1.0, rel=1e-9)


def test_the_weakest_direction_is_the_longest_axis_in_unit_diagonal_scaling():
    _, _, fit, _ = _fit_and_line("all", 1)
    d = np.sqrt(np.diag(fit.covariance))
    v = weakest_direction(fit.covariance) / d
    c = fit.covariance / np.outer(d, d)
    rayleigh = (v @ c @ v) / (v @ v)
    assert rayleigh == pytest.approx(np.linalg.eigvalsh(c)[-1], rel=1e-9)


def test_the_points_are_ordered_and_include_the_nominal_solution():
    _, _, fit, pts = _fit_and_line("all", 1)
    sig = [p.sigma for p in pts]
    assert sig == sorted(sig) and 0.0 in sig
    assert np.array_equal(pts[sig.index(0.0)].state, fit.state)


@pytest.mark.parametrize("nights", ["all", "one"])
def test_every_point_lies_on_its_hyperplane(nights):
    _, _, fit, pts = _fit_and_line(nights, 2)
    n = np.linalg.solve(fit.covariance, weakest_direction(fit.covariance))
    for p in pts:
        assert n @ (p.state - fit.state) == pytest.approx(p.sigma, abs=1e-3)


@pytest.mark.parametrize("nights", ["all", "one"])
def test_no_nearby_state_on_the_hyperplane_fits_better(nights):
    arc, ms, fit, pts = _fit_and_line(nights, 3)
    n = np.linalg.solve(fit.covariance, weakest_direction(fit.covariance))
    rng = np.random.default_rng(0)
    for p in (pts[0], pts[-1]):
        c = _chi2(arc, ms, p.state)
        assert c == pytest.approx(p.chi2, rel=1e-6)
        sd = np.sqrt(np.diag(p.covariance))
        for _ in range(6):
            d = rng.standard_normal(6) * sd * 0.3
            d -= n * (n @ d) / (n @ n)  # stay on the hyperplane
            assert _chi2(arc, ms, p.state + d) >= c - 1e-6


def test_on_a_long_arc_the_line_is_straight_and_the_chi_square_rises_as_sigma_squared():
    _, _, fit, pts = _fit_and_line("all", 4)
    v = weakest_direction(fit.covariance)
    n = np.linalg.inv(fit.covariance)
    assert len(pts) == 7
    for p in pts:
        off = p.state - (fit.state + p.sigma * v)
        assert off @ n @ off < 0.05 ** 2
        assert p.chi2 - fit.chi2 == pytest.approx(p.sigma ** 2, abs=0.05 * max(p.sigma ** 2, 1.0))


def test_on_one_night_the_line_follows_the_valley_below_the_straight_one():
    arc, ms, fit, pts = _fit_and_line("one", 4)
    v = weakest_direction(fit.covariance)
    for far in (pts[0], pts[-1]):
        assert abs(far.sigma) == 3.0
        straight = _chi2(arc, ms, fit.state + far.sigma * v) - fit.chi2
        assert far.chi2 - fit.chi2 < straight - 1.0  # the valley bends off the straight line


def test_the_nominal_covariance_is_the_fit_conditioned_on_sigma():
    _, _, fit, pts = _fit_and_line("all", 5)
    nominal = next(p for p in pts if p.sigma == 0.0)
    n = np.linalg.solve(fit.covariance, weakest_direction(fit.covariance))
    assert n @ nominal.covariance @ n == pytest.approx(0.0, abs=1e-9)


def test_a_side_stops_where_the_chi_square_has_risen_too_far():
    arc, ms, fit, _ = _fit_and_line("all", 6)
    pts = line_of_variations(arc.dynamics, arc.sensor, ms, fit, step=1.0, max_sigma=3.0,
                             max_delta_chi2=5.0, options=OPTS)
    assert [p.sigma for p in pts] == [-2.0, -1.0, 0.0, 1.0, 2.0]


def _half_sigma_line(seed: int):
    arc, ms, fit, _ = _fit_and_line("all", seed)
    return fit, line_of_variations(arc.dynamics, arc.sensor, ms, fit, step=0.5, max_sigma=4.0, options=OPTS)


def test_on_a_long_arc_the_weights_fall_as_the_gaussian_along_the_line():
    fit, pts = _half_sigma_line(7)
    w = line_weights(pts, 0.5, weakest_direction(fit.covariance))
    sig = np.array([p.sigma for p in pts])
    expected = np.exp(-0.5 * sig ** 2)
    np.testing.assert_allclose(w / w.max(), expected / expected.max(), atol=0.02)


def test_on_a_long_arc_draws_along_the_line_reproduce_the_fit_covariance():
    fit, pts = _half_sigma_line(7)
    v = weakest_direction(fit.covariance)
    x = sample_line(pts, 20000, np.random.default_rng(1), 0.5, v)
    n = np.linalg.inv(fit.covariance)
    c = np.cov(x.T)
    d = x.mean(axis=0) - fit.state
    assert d @ n @ d < 0.01  # the mean is the fit's, to 0.1 sigma
    assert np.trace(n @ c) == pytest.approx(6.0, rel=0.05)  # the covariance is the fit's...
    assert v @ n @ c @ n @ v == pytest.approx(1.0, rel=0.15)  # ...along the line too (+2 % by the spacing)


def test_a_line_of_one_point_is_drawn_along_the_weakest_direction():
    fit, pts = _half_sigma_line(8)
    nominal = [p for p in pts if p.sigma == 0.0]
    v = weakest_direction(fit.covariance)
    x = sample_line(nominal, 5000, np.random.default_rng(2), 0.5, v)
    s = (x - fit.state) @ np.linalg.solve(fit.covariance, v)
    assert np.max(np.abs(s)) <= 0.25 + 1e-6  # within half a step of the point, along the line
    assert np.std(s) == pytest.approx(0.5 / np.sqrt(12.0), rel=0.05)  # uniformly


def test_draws_are_reproducible_from_the_seed():
    fit, pts = _half_sigma_line(7)
    v = weakest_direction(fit.covariance)
    a = sample_line(pts, 100, np.random.default_rng(3), 0.5, v)
    b = sample_line(pts, 100, np.random.default_rng(3), 0.5, v)
    assert np.array_equal(a, b)


def test_the_summary_calls_a_long_arc_linear():
    _, _, fit, pts = _fit_and_line("all", 4)
    s = line_summary(pts, fit)
    assert s["linear"] and s["sigma_range"] == [-3.0, 3.0] and s["max_departure_sigma"] < 0.05


def test_the_summary_sees_one_night_bend():
    _, _, fit, pts = _fit_and_line("one", 4)
    s = line_summary(pts, fit)
    assert not s["linear"] and s["max_departure_sigma"] > 1.0


def test_a_line_whose_first_fits_failed_is_not_called_linear():
    """Only the nominal point (the first fits on both sides did not converge): it had been reported
    as 'leaves the straight line by at most 0 sigma', linear, for a fit 1e11 in Mahalanobis^2 off."""
    _, _, fit, pts = _fit_and_line("all", 4)
    nominal = [p for p in pts if p.sigma == 0.0]
    s = line_summary(nominal, fit)
    assert not s["followed"] and not s["linear"]
    one_side = [p for p in pts if p.sigma >= 0.0]
    assert not line_summary(one_side, fit)["linear"]
