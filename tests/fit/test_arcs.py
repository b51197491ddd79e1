"""Arcs: long gaps always split; shorter gaps are joined only when the fit of the later group
predicts the earlier within its covariance (tests/fit/arc_campaigns.py: two arcs of the 2:1 DRO
from MPC 711 and 809, with and without a velocity change between them)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.fitting.arcs import (LONG_GAP_DAYS, arc_choice, arc_sets, link_latest_arc, long_gap_arcs,
                                   observation_groups)
from cistrack.least_squares import fit_orbit
from cistrack.units import days_to_tu

from .arc_campaigns import two_arcs


def _days(*d):
    return days_to_tu(np.array(d, dtype=float))


def test_groups_split_only_where_the_gap_exceeds_the_threshold():
    t = _days(0, 0.3, 1.0, 4.5, 4.6, 40.0, 40.1)
    groups = observation_groups(t, 3.0)
    assert [g.rows.tolist() for g in groups] == [[0, 1, 2], [3, 4], [5, 6]]
    assert groups[0].gap_before_days == np.inf
    assert groups[1].gap_before_days == pytest.approx(3.5)
    assert [a.rows.tolist() for a in long_gap_arcs(t)] == [[0, 1, 2, 3, 4], [5, 6]]
    assert [a.n for a in long_gap_arcs(_days(0, LONG_GAP_DAYS))] == [2]     # exactly the threshold: one arc
    assert observation_groups(np.zeros(0)) == []


def test_a_bad_gap_or_choice_is_refused_naming_what_is_allowed():
    with pytest.raises(ConfigError, match="positive number of days"):
        observation_groups(_days(0, 1), 0.0)
    with pytest.raises(ConfigError, match="fit.arcs='newest'.*latest, each, all"):
        arc_choice("newest")
    assert arc_choice("each") == "each"


def test_arc_sets_give_the_latest_each_or_all():
    c = two_arcs(60.0)
    ms = c.measurements
    latest, = arc_sets(ms, "latest")
    first, second = arc_sets(ms, "each")
    everything, = arc_sets(ms, "all")
    assert len(everything) == len(ms) == len(first) + len(second)
    np.testing.assert_array_equal(latest.times, second.times)
    assert latest.times[0] - first.times[-1] > days_to_tu(LONG_GAP_DAYS)


def _refit(c):
    return lambda sub, start: fit_orbit(c.dynamics, c.sensor, sub, start.state, start.epoch)


def _latest_group_fit(c):
    ms = c.measurements
    sub = ms.subset(observation_groups(ms.times)[-1].rows)
    return fit_orbit(c.dynamics, c.sensor, sub, c.truth_at(sub.times[-1:])[0], sub.times[-1])


def test_one_orbit_across_a_six_day_gap_is_one_arc():
    c = two_arcs(6.0)
    linked = link_latest_arc(c.dynamics, c.sensor, c.measurements, _latest_group_fit(c), _refit(c))
    assert linked.arc.n == len(c.measurements) and linked.earlier == []
    assert [r.verdict for r in linked.rungs] == ["consistent"]
    assert linked.fit.converged and linked.fit.n_used == len(c.measurements)


def test_a_velocity_change_in_the_gap_breaks_the_link():
    c = two_arcs(6.0, dv_mps=5.0)
    first = _latest_group_fit(c)
    linked = link_latest_arc(c.dynamics, c.sensor, c.measurements, first, _refit(c))
    groups = observation_groups(c.measurements.times)
    assert linked.arc.n == groups[-1].n and len(linked.earlier) == 1
    assert linked.rungs[0].verdict == "broken" and "sigma" in linked.rungs[0].why
    assert linked.fit is first
