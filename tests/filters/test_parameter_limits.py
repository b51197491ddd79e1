"""Filter parameters whose extremes used to run for ever or crash inside filterpy are refused by name."""
from __future__ import annotations

import pytest

from cistrack.errors import ParameterError
from cistrack.plugin.registry import default_registry


def _filter(name: str, **params):
    return default_registry().create("filter", name, **params)


@pytest.mark.parametrize("factor", [1e9, 101.0, 0.0])
def test_a_reacquisition_factor_beyond_its_range_is_refused(factor):
    with pytest.raises(ParameterError, match="'reacquire_factor'"):
        _filter("pgm", reacquire_factor=factor)


def test_the_reacquisition_draws_count_in_the_memory_a_pgm_needs():
    plain = _filter("pgm", n_particles=10000).memory_need().bytes
    assert _filter("pgm", n_particles=10000, reacquire_factor=100.0).memory_need().bytes == pytest.approx(25 * plain)


@pytest.mark.parametrize("alpha", [1e-9, 1e200])
def test_a_ukf_alpha_whose_weights_cannot_be_computed_is_refused(alpha):
    with pytest.raises(ParameterError, match="'alpha'.*0.0001, 10"):
        _filter("ukf", alpha=alpha)


@pytest.mark.parametrize("alpha", [1e-4, 10.0])
def test_the_ukf_alpha_bounds_themselves_are_allowed(alpha):
    assert _filter("ukf", alpha=alpha).alpha == alpha


@pytest.mark.parametrize("name", ["pgm", "ukf", "enkf", "sir"])
def test_a_velocity_noise_larger_than_an_orbits_speed_is_refused(name):
    with pytest.raises(ParameterError, match="'velocity_noise_kms_per_sqrt_day'.*\\[0.0, 1.0\\]"):
        _filter(name, velocity_noise_kms_per_sqrt_day=1e9)


def test_state_bounds_that_no_particle_meets_are_named(tmp_path, capsys):
    from cistrack.cli.main import main

    assert main(["run", "quick", "--set", "filter.min_range_km=1e9", "--out", str(tmp_path / "r"), "--quiet"]) == 2
    assert "outside the state bounds (min_range_km = 1000000000.0" in capsys.readouterr().err


@pytest.mark.parametrize("key, value", [("n_particles", 2), ("n_particles", 6), ("n_members", 2)])
def test_an_enkf_of_fewer_members_than_a_full_rank_ensemble_is_refused_naming_the_floor(key, value):
    """Probe M12: n_particles = 2 had been taken and the run had ended 'diverged'. Six members span
    at most 5 of the state's 6 dimensions."""
    with pytest.raises(ParameterError, match=rf"'{key}' = {value} is invalid: must be >= 7 \(the state's 6 "
                                             r"dimensions \+ 1\).*rank at most"):
        _filter("enkf", **{key: value})


def test_an_enkf_of_seven_members_is_taken():
    assert _filter("enkf", n_particles=7).n_particles == 7


def test_cistrack_run_refuses_such_an_enkf_before_running(tmp_path, capsys):
    from cistrack.cli.main import main

    out = tmp_path / "r"
    with pytest.warns(UserWarning, match="n_components = 4 dropped"):  # quick's filter is the PGM
        assert main(["run", "quick", "--set", "filter.name=enkf", "--set", "filter.n_particles=2", "--out", str(out),
                     "--quiet"]) == 2
    assert "filter 'enkf': parameter 'n_particles' = 2 is invalid: must be >= 7" in capsys.readouterr().err
    assert not out.exists()
