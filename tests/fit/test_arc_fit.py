"""The latest arc's fit in the time base of a scenario that starts at the latest arc (earlier
arcs at negative times): a long gap leaves the earlier arc to the ladder, one orbit across a
short gap keeps the arc's fit, a velocity change behind a short gap replaces it by the fit of
the latest group."""
from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError
from cistrack.fitting.arc_fit import ladder_verdicts, latest_arc_fit
from cistrack.fitting.arcs import ArcSettings, arc_settings, long_gap_arcs, observation_groups
from cistrack.least_squares import fit_orbit

from .arc_campaigns import rebased, two_arcs


def _at_latest_arc(c):
    """The campaign counted from 30 minutes before its latest arc, and the fit of that arc."""
    arcs = long_gap_arcs(c.measurements.times)
    start = units.tu_to_utc(c.epoch, float(c.measurements.times[arcs[-1].rows[0]])) - timedelta(minutes=30)
    r = rebased(c, start.replace(second=0, microsecond=0))
    sub = r.measurements.subset(arcs[-1].rows)
    return r, arcs, fit_orbit(r.dynamics, r.sensor, sub, r.truth_at(sub.times[-1:])[0], sub.times[-1])


def test_a_long_gap_leaves_the_earlier_arc_to_the_ladder():
    r, arcs, fit = _at_latest_arc(two_arcs(60.0))
    assert r.measurements.times[arcs[0].rows].max() < 0
    out = latest_arc_fit(r.dynamics, r.sensor, r.measurements, fit)
    assert out.fit is fit
    np.testing.assert_array_equal(out.rows, arcs[-1].rows)
    assert [s.n for s in out.earlier] == [arcs[0].n]
    assert [g.verdict for g in out.ladder] == ["consistent"] and ladder_verdicts(out.ladder) == "1 consistent"
    assert "2 arcs more than 30 days apart" in out.notes[0]


def test_one_orbit_across_a_short_gap_keeps_the_arcs_fit():
    r, _arcs, fit = _at_latest_arc(two_arcs(6.0))
    out = latest_arc_fit(r.dynamics, r.sensor, r.measurements, fit)
    assert out.fit is fit and out.earlier == [] and out.ladder == [] and out.notes == []
    assert out.rows.size == len(r.measurements)


def test_a_velocity_change_behind_a_short_gap_leaves_the_earlier_group_out():
    r, _arcs, fit = _at_latest_arc(two_arcs(6.0, dv_mps=5.0))
    out = latest_arc_fit(r.dynamics, r.sensor, r.measurements, fit)
    groups = observation_groups(r.measurements.times)
    np.testing.assert_array_equal(out.rows, groups[-1].rows)
    assert out.fit is not fit and out.fit.converged and out.fit.n_used + out.fit.n_rejected == groups[-1].n
    assert [g.verdict for g in out.ladder] == ["broken"] and "left out" in out.notes[0]
    truth = r.truth_at(np.array([out.fit.epoch]))[0]
    assert out.fit.mahalanobis2(truth) < 30          # the later orbit, not a compromise


def test_arc_settings_take_their_keys_and_leave_the_rest():
    settings, rest = arc_settings({"arcs": "each", "arc_gap_days": 30, "epoch": "middle"})
    assert settings == ArcSettings("each", 30.0, 3.0) and rest == {"epoch": "middle"}
    assert arc_settings({})[0] == ArcSettings()
    with pytest.raises(ConfigError, match="fit.arc_gap_days=-1"):
        arc_settings({"arc_gap_days": -1})
    with pytest.raises(ConfigError, match="fit.link_gap_days=40.*must not exceed"):
        arc_settings({"link_gap_days": 40})
