"""The validation helpers a plugin author calls in a constructor, and Registry.create, used as a
third party would: numpy's scalars are numbers, a misspelt parameter is named with the ones the
component takes, and a helper misused (NaN bounds, one string of choices, no component) says so."""
from __future__ import annotations

import re

import numpy as np
import pytest

from cistrack.api import check_choice, check_int, check_positive, check_range, default_registry, load_registry
from cistrack.errors import ParameterError


@pytest.mark.parametrize("value", [np.int64(500), np.int32(500), np.float64(500.0), np.float32(500.0), 500])
def test_numpy_integers_and_whole_floats_are_integers(value):
    assert default_registry().create("filter", "pgm", n_particles=value).n_particles == 500
    assert check_int(None, "n", value) == 500


@pytest.mark.parametrize("value", [True, np.bool_(True), 2.5, "3"])
def test_booleans_fractions_and_text_are_not_integers(value):
    with pytest.raises(ParameterError, match="parameter 'n' = .* is invalid: must be an integer"):
        check_int(None, "n", value)


def test_a_numpy_float_is_a_number_for_the_range_checks():
    assert check_positive(None, "x", np.float32(0.5)) == 0.5
    assert check_range(None, "x", np.int64(1), 0.0, 2.0) == 1.0


def test_a_misspelt_parameter_names_the_component_and_the_parameters_it_takes():
    with pytest.raises(ParameterError, match=r"filter 'pgm': unknown parameter 'bogus'; its parameters: "
                                             r"n_particles, n_components"):
        default_registry().create("filter", "pgm", bogus=1)


def test_nan_bounds_are_refused_rather_than_letting_every_value_through():
    with pytest.raises(ValueError, match="the bounds must be numbers"):
        check_range(None, "x", 0.5, float("nan"), 1.0)


def test_one_string_of_choices_is_one_choice_not_its_letters():
    assert check_choice(None, "mode", "abc", "abc") == "abc"
    with pytest.raises(ParameterError, match="must be one of 'abc'"):
        check_choice(None, "mode", "a", "abc")


def test_a_check_called_without_a_component_names_the_parameter():
    with pytest.raises(ParameterError, match=r"^parameter 'x' = -1 is invalid: must be > 0$"):
        check_positive(None, "x", -1)


def test_a_registry_told_to_autoload_something_other_than_yes_or_no_refuses():
    with pytest.raises(TypeError, match=r"autoload_third_party=5: give True, False or None"):
        load_registry(5)



def _loose(star: str):
    """A clusterer whose constructor takes ``*args`` (``star`` "*") or ``**kwargs`` (``star`` "**")."""
    from cistrack.api import Clusterer

    class Loose(Clusterer):
        def __init__(self, n_components: int = 2, *args, **kwargs):
            self.n_components = n_components

        def cluster(self, x, rng):
            return np.zeros(len(x), dtype=np.intp)

    if star == "**":
        def init(self, n_components: int = 2, **kwargs):
            self.n_components = n_components
        Loose.__init__ = init
    return Loose()


@pytest.mark.parametrize("star, name", [("*", "args"), ("**", "kwargs")])
def test_the_conformance_check_names_a_catch_all_parameter_as_written(star, name):
    """Probe L10: ``**kwargs`` had been named ``*kwargs/**kwargs``."""
    from cistrack.testing.checks_params import check_parameters_declared

    with pytest.raises(AssertionError, match=rf"^__init__ takes {re.escape(star + name)}: declare every parameter"):
        check_parameters_declared(_loose(star))
