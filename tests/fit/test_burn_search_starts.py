"""Where the burn search's full fits start (cistrack.least_squares.burn_search): a gap's fit is made
with the ballistic fit's rejections out of its first pass as well as with every observation in it,
an unconverged one is fitted once more, the time check fits the burn's own gap from the ballistic
fit too, and a retry doubted for its own reason says so (cistrack.fitting.maneuver_search._retried)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from cistrack.least_squares import burn_search
from cistrack.least_squares.errors import FitError
from cistrack.least_squares.impulse_fit import BurnArc, BurnEstimate, ImpulseFit

ARC = BurnArc(None, None, None)
REJECTED = np.array([False, True, False, False])


def _fit(cost: float, converged: bool = True, t: float = 1.0, dv: float = 0.3) -> ImpulseFit:
    """An ImpulseFit of one burn at ``t`` (TU) whose capped cost is ``cost`` (ten observations)."""
    fit = SimpleNamespace(residuals=SimpleNamespace(chi2=np.full(10, cost / 10.0), rejected=np.zeros(10, dtype=bool)),
                          rejection_threshold=np.inf, converged=converged, state=np.zeros(6), epoch=0.0)
    burn = BurnEstimate(t, np.array([dv, 0.0, 0.0]), np.eye(3) * 0.01)
    return ImpulseFit([burn], fit, 0, np.array([cost]), np.array([t]))


def _about():
    return SimpleNamespace(state=np.zeros(6), epoch=0.0, residuals=SimpleNamespace(rejected=REJECTED))


def _fake_fit_impulse(monkeypatch, with_all, with_r):
    """burn_search.fit_impulse giving ``with_all`` (every observation in the first pass) or
    ``with_r`` (the rejections left out), a FitError for None; the calls' ``rejected`` recorded."""
    calls = []

    def fake(arc, state, t0, tbs, *, known=(), rejected=None):
        calls.append(rejected)
        out = with_all if rejected is None else with_r
        if out is None:
            raise FitError("fit: the normal matrix is not positive definite")
        return out

    monkeypatch.setattr(burn_search, "fit_impulse", fake)
    return calls


def test_a_gap_fit_is_made_with_the_ballistic_rejections_out_of_its_first_pass_too_and_the_cheaper_kept(monkeypatch):
    """A survey set's 0.3 m/s burn: with a gross outlier in the first pass, 1.77 m/s at capped cost
    156.8; with the ballistic fit's rejections left out, 0.275 m/s at 65.3."""
    calls = _fake_fit_impulse(monkeypatch, _fit(156.8, dv=1.77), _fit(65.3, dv=0.275))
    got = burn_search._gap_starts(ARC, _about(), np.array([1.0]), [])
    assert calls[0] is None and np.array_equal(calls[1], REJECTED)
    assert got.searched.magnitude_ms == pytest.approx(0.275)


def test_a_gap_fit_with_every_observation_stays_when_it_is_the_cheaper(monkeypatch):
    """The ballistic fit's rejections can be one whole side of the burn: leaving them out is a
    second start, not a replacement."""
    _fake_fit_impulse(monkeypatch, _fit(40.0, dv=0.3), _fit(90.0, dv=2.0))
    assert burn_search._gap_starts(ARC, _about(), np.array([1.0]), []).searched.magnitude_ms == pytest.approx(0.3)


def test_a_gap_fit_that_fails_with_every_observation_is_made_without_the_rejections(monkeypatch):
    """A survey set's gap fits failed (normal matrix not positive definite) with the gross outlier in
    the first pass; without it the fit converged, its cost 280 below the ballistic fit's."""
    _fake_fit_impulse(monkeypatch, None, _fit(44.1, dv=0.211))
    assert burn_search._gap_starts(ARC, _about(), np.array([1.0]), []).searched.magnitude_ms == pytest.approx(0.211)
    _fake_fit_impulse(monkeypatch, None, None)
    assert burn_search._gap_starts(ARC, _about(), np.array([1.0]), []) is None


def test_a_gap_fit_is_made_once_when_the_fit_it_starts_from_rejected_nothing(monkeypatch):
    calls = _fake_fit_impulse(monkeypatch, _fit(40.0), _fit(30.0))
    about = _about()
    about.residuals = SimpleNamespace(rejected=np.zeros(4, dtype=bool))
    assert burn_search._gap_starts(ARC, about, np.array([1.0]), []).costs.min() == pytest.approx(40.0)
    assert calls == [None]


def test_an_unconverged_gap_fit_is_fitted_once_more_from_where_it_stopped(monkeypatch):
    """A survey set's gap fit stopped unconverged at cost 85.8 (the burn's test takes converged fits
    only); fitted once more from there, its burn and time kept, it converges cheaper."""
    moved = []

    def refit(arc, fit, burns, k, tb):
        moved.append((fit, k, tb))
        return _fit(42.0, converged=True, t=tb, dv=0.36)

    monkeypatch.setattr(burn_search, "refit_moved", refit)
    stopped = _fit(85.8, converged=False, t=1.0, dv=1.6)
    got = burn_search._continued(ARC, stopped)
    assert moved == [(stopped.fit, 0, 1.0)]
    assert got.fit.converged and got.searched.magnitude_ms == pytest.approx(0.36)
    assert got.costs.min() == pytest.approx(42.0)  # the gap fits are compared by these


def test_a_converged_gap_fit_is_not_fitted_again_and_a_dearer_continuation_is_dropped(monkeypatch):
    monkeypatch.setattr(burn_search, "refit_moved", lambda *a: _fit(120.0, converged=True))
    done = _fit(50.0)
    assert burn_search._continued(ARC, done) is done
    stopped = _fit(85.8, converged=False)
    assert burn_search._continued(ARC, stopped) is stopped


def test_the_time_check_fits_the_burns_gap_from_the_ballistic_fit_its_delta_v_from_zero(monkeypatch):
    """Trial times refitted from the search's fit stay in its minimum: the burn's own gap is fitted
    at GAP_POINTS times from the ballistic fit too (its rejections out of the first pass: refit_moved),
    the burn's delta-v from zero, the other burns' from theirs."""
    calls = []

    def refit(arc, fit, burns, k, tb):
        calls.append((fit, [b.delta_v_ms.copy() for b in burns], k, tb))
        return _fit(30.0, t=tb)

    monkeypatch.setattr(burn_search, "refit_moved", refit)
    other = BurnEstimate(5.0, np.array([0.0, 1.0, 0.0]), np.eye(3))
    b = BurnEstimate(1.5, np.array([0.9, 0.0, 0.0]), np.eye(3))
    ballistic = SimpleNamespace(name="ballistic")
    found = burn_search.ManeuverSearch(None, None, [b, other], [(1.0, 2.0), (4.0, 6.0)], ballistic=ballistic)
    got = burn_search._from_ballistic(ARC, found, b, (1.0, 2.0), 50.0)
    n = burn_search.GAP_POINTS
    assert [c[3] for c in calls] == pytest.approx(1.0 + (np.arange(n) + 0.5) / n)
    assert all(c[0] is ballistic and c[2] == 0 for c in calls)
    assert all(np.all(c[1][0] == 0.0) and np.all(c[1][1] == other.delta_v_ms) for c in calls)
    assert [g[1] for g in got] == pytest.approx([-20.0] * n)
    assert burn_search._from_ballistic(ARC, burn_search.ManeuverSearch(None, None, [b], [(1.0, 2.0)]), b,
                                       (1.0, 2.0), 50.0) == []


def test_a_retry_doubted_for_its_own_reason_says_so_beside_the_first_searchs(monkeypatch):
    """The retry's reason had never reached fit.json: the first search's words alone were quoted."""
    from cistrack.fitting import maneuver_search as ms

    first = ms._Outcome(None, None, [], "the burn the search kept (5.26 +- 14.4 m/s) is within 3 sigma of none")
    again = ms._Outcome(None, None, [], "the burn the search kept (0.204 +- 0.248 m/s) is within 2 sigma of none")
    monkeypatch.setattr(ms, "_measured", lambda ctx, one, say, f: again)
    got = ms._retried(None, None, first, lambda m: None)
    assert got.doubt.startswith(first.doubt) and got.doubt.endswith(again.doubt)
    assert "searched again" in got.doubt
    monkeypatch.setattr(ms, "_measured", lambda ctx, one, say, f: f)  # the same burns: the first's verdict stands
    assert ms._retried(None, None, first, lambda m: None) is first
