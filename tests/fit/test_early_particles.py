"""The filter over the first hours (cistrack.fitting.early_seed) runs with at most
EARLY_PARTICLES particles in its IOD and its filter; a smaller count, and the other settings, are
the scenario's."""
from __future__ import annotations

from cistrack.fitting.early_seed import EARLY_PARTICLES, early_particles


def test_larger_counts_are_capped_in_the_iod_and_the_filter():
    raw = {"iod": {"name": "x", "n_particles": 4 * EARLY_PARTICLES}, "filter": {"name": "pgm", "n_particles": 8000}}
    out = early_particles(raw)
    assert out["iod"] == {"name": "x", "n_particles": EARLY_PARTICLES}
    assert out["filter"] == {"name": "pgm", "n_particles": EARLY_PARTICLES}
    assert raw["iod"]["n_particles"] == 4 * EARLY_PARTICLES          # the scenario's own table is kept


def test_smaller_counts_and_tables_without_one_are_left_as_they_are():
    raw = {"iod": {"name": "x", "n_particles": 200}, "filter": {"name": "ekf"}, "sensor": {"n_particles": 10**6}}
    assert early_particles(raw) == raw


def test_a_value_that_is_not_an_integer_is_left_for_the_scenarios_check():
    raw = {"iod": {"n_particles": "many"}, "filter": {"n_particles": True}}
    assert early_particles(raw) == raw
