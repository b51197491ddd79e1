"""`cistrack fit` searches a suspect arc a second time with burns started where the orbits of a
gap's two sides meet; that search's burns replace the first search's verdict only when they do
not clash with it (cistrack.fitting.maneuver_search._clash)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack.fitting.maneuver_search import _clash, _Outcome
from cistrack.least_squares.burn_search import ManeuverSearch
from cistrack.least_squares.impulse_fit import BurnEstimate

GAP = (0.5, 1.7)


def _search(t: float, dv_ms: float, windows):
    burns = [BurnEstimate(t, np.array([dv_ms, 0.0, 0.0]), np.eye(3) * 0.01, 0.01, np.zeros(3))]
    return ManeuverSearch(result=None, dynamics=None, burns=burns, windows=list(windows))


def test_a_burn_in_the_gap_the_first_time_check_left_undetermined_clashes():
    """An unseen NRHO set: the first search's check found two times in a five-day gap; a 5.8 m/s
    burn started where the sides meet fitted at a third, 140 sigma from the truth."""
    first = _Outcome(_search(1.2, 1.4, [GAP]), None, [], "the burn's time is not determined", (GAP,))
    again = _Outcome(_search(0.6, 5.8, [GAP]), None, [], "")
    assert "the cost has several minima there" in _clash(first, again)


def test_a_burn_where_the_first_search_found_none_does_not_clash():
    first = _Outcome(ManeuverSearch(None, None), None, [],
                     "no impulsive burn in the gaps between the observations explains it")
    again = _Outcome(_search(0.6, 1.0, [GAP]), None, [], "")
    assert _clash(first, again) == ""


def _costed(search: ManeuverSearch, cost: float) -> ManeuverSearch:
    """``search`` with a fit whose capped cost is ``cost`` (ten observations, none rejected)."""
    chi2 = np.full(10, cost / 10.0)
    search.result = SimpleNamespace(residuals=SimpleNamespace(chi2=chi2), rejection_threshold=np.inf)
    return search


def test_a_first_burn_that_fits_as_well_and_lies_outside_three_sigma_clashes():
    first = _Outcome(_costed(_search(1.2, 1.4, [GAP]), 88.0), None, [], "it still rejects 8 of 38 observations")
    again = _Outcome(_costed(_search(0.6, 5.8, [(0.2, 0.9)]), 80.0), None, [], "")
    assert "the arc does not determine which" in _clash(first, again)


def test_a_first_burn_that_fits_clearly_worse_does_not_clash():
    first = _Outcome(_costed(_search(1.2, 1.4, [GAP]), 150.0), None, [], "it still rejects 8 of 38 observations")
    again = _Outcome(_costed(_search(0.6, 5.8, [(0.2, 0.9)]), 80.0), None, [], "")
    assert _clash(first, again) == ""
