"""The custody-ceiling reference (benchmarks/custody_ceiling.py) against closed-form cases: an exact
filter's truth leaves the 0.997 region with probability 0.003 at each update."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from custody_ceiling import calibrated_losses  # noqa: E402

from cistrack.evaluation.custody import CustodyRule  # noqa: E402

N = 400_000
TOL = 5 * np.sqrt(0.003 * 0.997 / N)
NO_LOGLIK = CustodyRule(loglik_threshold=-np.inf)


def _problem(n_updates: int, r: float):
    H = np.eye(6)[:2]
    return np.eye(6), [np.eye(6)] * n_updates, [H] * n_updates, [r * np.eye(2)] * n_updates


@pytest.mark.parametrize("consecutive", [1, 2])
def test_one_update_loses_custody_only_with_a_one_update_rule_and_then_with_probability_0_003(consecutive):
    lost, nees = calibrated_losses(*_problem(1, 0.5), N, np.random.default_rng(0),
                                   CustodyRule(loglik_threshold=-np.inf, hdr_consecutive=consecutive))
    assert abs(nees[0] - 6.0) < 0.05
    assert abs(lost.mean() - (0.003 if consecutive == 1 else 0.0)) < TOL


def test_an_update_that_adds_no_information_keeps_the_error_so_two_in_a_row_cost_0_003():
    lost, _ = calibrated_losses(*_problem(2, 1e12), N, np.random.default_rng(1), NO_LOGLIK)
    assert abs(lost.mean() - 0.003) < TOL


def test_the_posterior_nees_of_the_exact_filter_averages_six_at_every_update():
    _, nees = calibrated_losses(*_problem(5, 0.1), N, np.random.default_rng(2), NO_LOGLIK)
    assert np.all(np.abs(nees - 6.0) < 0.05)
