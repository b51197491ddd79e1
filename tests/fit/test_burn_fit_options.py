"""Every fit with a burn that `cistrack fit` makes gets at least BURN_ITERATIONS Levenberg-Marquardt
iterations per pass: the state and a delta-v of a survey arc form an ill-conditioned valley, and
a right 1 m/s burn (cost 41,384 below the ballistic fit's, weighted RMS 0.94) had stopped at the
ballistic default of 30, not converged, and was not kept."""
from __future__ import annotations

from dataclasses import replace

from cistrack.fitting.maneuver_search import fit_options
from cistrack.least_squares.burn_search import BURN_ITERATIONS, burn_fit_options
from cistrack.least_squares.options import FitOptions


def test_a_burn_fit_gets_more_iterations_than_the_ballistic_default():
    assert FitOptions().max_iterations < BURN_ITERATIONS == burn_fit_options(FitOptions()).max_iterations


def test_a_larger_limit_the_user_set_is_kept():
    assert burn_fit_options(FitOptions(max_iterations=500)).max_iterations == 500


def test_nothing_else_of_the_options_changes():
    opts = FitOptions(reject_sigma=4.0, area_to_mass="solve")
    assert burn_fit_options(opts) == replace(opts, max_iterations=BURN_ITERATIONS)


def test_the_refits_with_the_burns_found_get_them_too():
    from types import SimpleNamespace

    assert fit_options(SimpleNamespace(parameter_names=("delta_v_1_x",))).max_iterations == BURN_ITERATIONS
