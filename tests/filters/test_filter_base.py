"""The built-in filters share one base for naming, the initialisation check, the predict wrapper
and diagnostics."""
from __future__ import annotations

import pytest

from cistrack.errors import FilterError
from cistrack.interfaces.filter import FilterBase

FILTERS = ["pgm", "pgm-paper", "ukf", "enkf", "sir"]


@pytest.mark.parametrize("name", FILTERS)
def test_builtin_filters_share_the_filter_base(registry, name):
    assert issubclass(registry.get("filter", name).factory, FilterBase)


@pytest.mark.parametrize("name", FILTERS)
def test_predict_before_initialize_names_the_filter(registry, name):
    filt = registry.create("filter", name)
    with pytest.raises(FilterError, match=f"filter '{name}': call initialize"):
        filt.predict(1.0)


def test_a_filter_without_its_prediction_step_cannot_be_built():
    class NoPrediction(FilterBase):
        def _is_initialized(self):
            return False

        def initialize(self, cloud, dynamics, sensor, rng):
            pass

        def update(self, measurement):
            pass

        @property
        def belief(self):
            return None

    with pytest.raises(TypeError, match="_predict_to"):
        NoPrediction()
