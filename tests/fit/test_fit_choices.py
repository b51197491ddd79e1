"""The `--set fit.*` settings of `cistrack fit`: checked before anything runs, naming the key."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError
from cistrack.fitting.from_observations import fit_choices


def test_defaults_are_the_last_observation_and_no_prior():
    c = fit_choices({})
    assert (c.epoch, c.prior) == ("last", "none")


def test_fit_options_pass_through():
    c = fit_choices({"reject_sigma": 4.0, "max_iterations": 50})
    assert c.options.reject_sigma == 4.0 and c.options.max_iterations == 50


def test_an_unknown_epoch_is_refused_naming_the_choices():
    with pytest.raises(ConfigError, match="fit.epoch='end'.*last, middle, first"):
        fit_choices({"epoch": "end"})


def test_an_unknown_prior_is_refused_naming_the_choices():
    with pytest.raises(ConfigError, match="fit.prior='strong'.*'none'.*'filter'"):
        fit_choices({"prior": "strong"})


def test_a_bad_option_value_is_refused_naming_it():
    with pytest.raises(ConfigError, match="reject_sigma"):
        fit_choices({"reject_sigma": -1.0})


def test_no_line_of_variations_by_default():
    assert fit_choices({}).lov == 0.0


def test_the_line_of_variations_is_asked_in_sigmas():
    assert fit_choices({"lov": 3}).lov == 3.0


@pytest.mark.parametrize("bad", [-1, 0.2, 50, "wide", True])
def test_a_bad_line_of_variations_is_refused_naming_it(bad):
    with pytest.raises(ConfigError, match="fit.lov=.*0.5 to 20"):
        fit_choices({"lov": bad})
