"""The one factor by which a fit's sigmas are widened for its noise scale (its square scales the
covariance wherever a fit's covariance is exported, predicted, sampled or judged)."""
from __future__ import annotations

import pytest

from cistrack.least_squares.result import sigma_factor


def test_a_noise_scale_above_one_widens_the_sigmas_by_itself():
    assert sigma_factor(1.25) == 1.25


@pytest.mark.parametrize("noise_scale", [0.4, 1.0, float("nan"), float("inf")])
def test_a_noise_scale_at_most_one_or_undefined_leaves_the_sigmas_as_they_are(noise_scale):
    assert sigma_factor(noise_scale) == 1.0
