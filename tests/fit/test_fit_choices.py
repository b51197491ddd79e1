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


def test_the_line_of_variations_is_auto_by_default_and_0_turns_it_off():
    assert fit_choices({}).lov is None and fit_choices({"lov": "auto"}).lov is None
    assert fit_choices({"lov": 0}).lov == 0.0


def test_the_line_of_variations_is_asked_in_sigmas():
    assert fit_choices({"lov": 3}).lov == 3.0


@pytest.mark.parametrize("bad", [-1, 0.2, 50, "wide", True])
def test_a_bad_line_of_variations_is_refused_naming_it(bad):
    with pytest.raises(ConfigError, match="fit.lov=.*0.5 to 20"):
        fit_choices({"lov": bad})


def test_a_date_for_the_fit_epoch_is_shown_as_typed():
    from datetime import datetime, timezone

    with pytest.raises(ConfigError, match=r"fit\.epoch=2030-01-01T00:00:00\+00:00: must be one of last"):
        fit_choices({"epoch": datetime(2030, 1, 1, tzinfo=timezone.utc)})


@pytest.mark.parametrize("item", ["duration_days=1", "epoch=2026-03-01T00:00:00Z", "name=x"])
def test_the_span_and_name_the_observations_set_are_refused_as_settings(tmp_path, capsys, item):
    from cistrack.cli.main import main

    assert main(["fit", str(tmp_path / "none.psv"), "--set", item, "--out", str(tmp_path / "o")]) == 2
    assert f"--set {item.split('=')[0]}: cistrack fit sets" in capsys.readouterr().err


def test_the_old_default_reach_of_the_line_still_imports_with_a_deprecation_warning():
    with pytest.warns(DeprecationWarning, match="AUTO_DELTA_CHI2"):
        from cistrack.fitting.from_observations import AUTO_LOV_SIGMAS
    assert AUTO_LOV_SIGMAS == 3.0


def test_a_largest_damping_below_the_first_is_refused_naming_both():
    with pytest.raises(ConfigError, match=r"fit\.max_damping=1e-09: must exceed fit\.damping \(0\.001\)"):
        fit_choices({"max_damping": 1e-9})
