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


def test_an_undetermined_noise_scale_is_written_in_words_never_nan():
    """With 0 degrees of freedom the summary, the OEM COMMENT and the error had read 'noise scale nan'."""
    from cistrack.least_squares.result import noise_scale_text

    assert noise_scale_text(float("nan")) == "undetermined (no degrees of freedom)"


def test_a_determined_noise_scale_is_written_as_a_number():
    from cistrack.least_squares.result import noise_scale_text

    assert noise_scale_text(0.8512345) == "0.8512"
