"""Every option of the least squares (FitOptions, `--set fit.KEY=VALUE`) is checked for its type
before its range: a value of the wrong type is refused with a ParameterError (ConfigError from
`--set`) naming the option, the value and what is allowed, never a Python-internal message."""
from __future__ import annotations

from dataclasses import fields

import pytest

from cistrack.errors import ConfigError, ParameterError
from cistrack.fitting.from_observations import fit_choices
from cistrack.least_squares import FitOptions

ALL_OPTIONS = [f.name for f in fields(FitOptions)]


@pytest.mark.parametrize("name", ALL_OPTIONS)
@pytest.mark.parametrize("value", ["abc", {"a": 1}], ids=["text", "table"])
def test_a_value_of_the_wrong_type_is_refused_naming_the_option_and_what_is_allowed(name, value):
    with pytest.raises(ParameterError, match=rf"^fit option {name} = {value!r}: must "):
        FitOptions(**{name: value})


@pytest.mark.parametrize("name", ["damping", "damping_factor", "max_reject_fraction", "max_rms"])
def test_a_bool_is_not_a_number(name):
    with pytest.raises(ParameterError, match=rf"fit option {name} = True: must be a"):
        FitOptions(**{name: True})


def test_a_list_for_a_number_is_refused_saying_a_number_is_wanted():
    with pytest.raises(ParameterError, match=r"damping_factor = \[1, 2\]: must be a finite number > 1"):
        FitOptions(damping_factor=[1, 2])


def test_sensor_steps_of_booleans_are_refused():
    with pytest.raises(ParameterError, match="sensor_steps = .*6 positive numbers"):
        FitOptions(sensor_steps=[True] * 6)


@pytest.mark.parametrize("item, why", [
    ({"damping_factor": "abc"}, r"--set fit\.damping_factor='abc': must be a finite number > 1$"),
    ({"max_reject_fraction": "abc"}, r"--set fit\.max_reject_fraction='abc': must be a number in \[0, 1\)$"),
    ({"sensor_steps": "abc"}, r"--set fit\.sensor_steps='abc': must be 6 positive numbers"),
    ({"max_reject_fraction": {"a": 1}}, r"--set fit\.max_reject_fraction=\{'a': 1\}: must be a number"),
])
def test_the_set_key_of_a_wrongly_typed_option_is_named(item, why):
    with pytest.raises(ConfigError, match=why):
        fit_choices(item)
