"""The conformance checks of the PGM's steps tell a wrong step from a right one."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.api import ComponentUpdate, PosteriorDraw
from cistrack.testing import ConformanceError, check_plugin


class PriorOnlyUpdate(ComponentUpdate):
    """Returns the prior unchanged: what a step that ignores the measurement would do."""

    def update(self, moments, residuals, R):
        m = moments.mean_x.shape[0]
        return moments.mean_x.copy(), moments.pxx.copy(), np.zeros(m)


class PriorMeansDraw(PosteriorDraw):
    """Draws around the prior clusters' means instead of the posterior's."""

    def draw(self, prior, posterior, n, rng):
        labels = rng.integers(0, posterior.n_components, n)
        return prior.means[labels] + 1e-9 * rng.standard_normal((n, prior.means.shape[1])), labels


def test_an_update_that_ignores_the_measurement_fails_the_kalman_check():
    with pytest.raises(ConformanceError, match="update_is_kalman_for_linear_measurements"):
        check_plugin(PriorOnlyUpdate)


def test_a_draw_that_ignores_the_posterior_fails_the_posterior_check():
    with pytest.raises(ConformanceError, match="draw_follows_the_posterior"):
        check_plugin(PriorMeansDraw)


@pytest.mark.parametrize("name", ["iterated", "ensemble"])
def test_the_built_in_updates_are_the_kalman_filter_on_linear_measurements(name):
    from cistrack.api import default_registry

    cls = default_registry().get("pgm-update", name).factory
    assert check_plugin(cls).passed
