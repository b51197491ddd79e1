"""The largest burn a fit's observations would not show, gap by gap
(cistrack.least_squares.burn_sensitivity), on a linear problem where least squares is exact: a
force-free particle whose position is measured in three sessions. The burn it reports, added to
noise-free observations, raises the ballistic refit's chi-square by exactly 9 (3 sigma); twice
as large, by 36."""
from __future__ import annotations

import numpy as np
import pytest

from .linear_components import FreeParticle, PositionSensor, burned_free_particle
from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.burn_sensitivity import HIDDEN_SIGMAS, burn_sensitivity
from cistrack.least_squares.impulse_fit import MS_PER_VU
from cistrack.model.measurement import MeasurementSet

X0 = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])
SESSIONS = (0.0, 1.0, 2.0)   # TU; a session is 4 exposures over 0.03 TU (3 hours apart is 0.028 TU)
SIGMA = 1e-6
NO_REJECTION = FitOptions(reject_outliers=False)


def _times(last: int = 4) -> np.ndarray:
    return np.concatenate([s + np.linspace(0.0, 0.009, 4 if k < 2 else last) for k, s in enumerate(SESSIONS)])


def _measured(times: np.ndarray, dv: np.ndarray = np.zeros(3), tb: float = 0.5) -> MeasurementSet:
    sen = PositionSensor(sigma=SIGMA)
    ms = sen.simulate(np.array([burned_free_particle(X0, dv, tb, t) for t in times]), times,
                      np.random.default_rng(0))
    exact = np.array([burned_free_particle(X0, dv, tb, t)[:3] for t in times])
    return MeasurementSet(ms.times, exact, ms.sigmas, ms.names, dict(ms.meta), ms.sites, ms.kinds,
                          dict(ms.site_table))


def _ballistic_fit(ms: MeasurementSet):
    return fit_orbit(FreeParticle(), PositionSensor(sigma=SIGMA), ms, X0, float(ms.times[-1]), options=NO_REJECTION)


@pytest.fixture(scope="module")
def gaps():
    times = _times()
    ms = _measured(times)
    return times, burn_sensitivity(_ballistic_fit(ms), FreeParticle(), PositionSensor(sigma=SIGMA), ms)


def test_each_gap_between_sessions_is_reported(gaps):
    times, out = gaps
    assert [(g.start, g.end) for g in out] == [(times[3], times[4]), (times[7], times[8])]
    assert all(g.start < g.t_worst < g.end for g in out)


@pytest.mark.parametrize("times_size, cost", [(1.0, HIDDEN_SIGMAS ** 2), (2.0, 4.0 * HIDDEN_SIGMAS ** 2)])
def test_the_reported_burn_raises_the_ballistic_refits_chi_square_by_nine(gaps, times_size, cost):
    times, out = gaps
    for g in out:
        dv = g.direction * g.largest_hidden_ms * times_size / MS_PER_VU
        refit = _ballistic_fit(_measured(times, dv, g.t_worst))
        assert refit.chi2 == pytest.approx(cost, rel=1e-3)


def test_a_gap_followed_by_fewer_exposures_hides_larger_burns(gaps):
    """One exposure after the last gap instead of four."""
    short = _times(last=1)
    ms = _measured(short)
    out = burn_sensitivity(_ballistic_fit(ms), FreeParticle(), PositionSensor(sigma=SIGMA), ms)
    assert out[-1].largest_hidden_ms > 1.2 * gaps[1][-1].largest_hidden_ms


def test_one_session_has_no_gap():
    ms = _measured(np.linspace(0.0, 0.009, 6))
    assert burn_sensitivity(_ballistic_fit(ms), FreeParticle(), PositionSensor(sigma=SIGMA), ms) == []


@pytest.mark.parametrize("size, words", [(0.512, "a burn of 0.51 m/s between"), (25.01, "a burn of 25 m/s between"),
                                         (4069.0, "a burn of any size between"), (np.inf, "a burn of any size between")])
def test_the_summary_says_the_last_gaps_figure_in_plain_numbers_and_any_size_beyond_100_m_s(size, words):
    from datetime import datetime, timezone

    from cistrack.fitting.fit_summary import _hidden_burn_line
    from cistrack.least_squares.burn_sensitivity import GapSensitivity

    line = _hidden_burn_line(GapSensitivity(1.0, 1.2, size, 1.19, np.array([1.0, 0.0, 0.0])),
                             datetime(2026, 1, 1, tzinfo=timezone.utc))
    assert words in line and "e+" not in line


def test_the_summary_names_the_earlier_gap_that_hides_the_largest_burn():
    """A survey fit left "converged" by a 0.3 m/s burn in a six-day gap had named only the last gap."""
    from datetime import datetime, timezone

    from cistrack.fitting.fit_summary import _earlier_gap_line
    from cistrack.least_squares.burn_sensitivity import GapSensitivity

    epoch = datetime(2026, 1, 1, tzinfo=timezone.utc)
    gaps = [GapSensitivity(a, a + 0.5, x, a + 0.4, np.array([1.0, 0.0, 0.0])) for a, x in ((1.0, 0.1), (2.0, 12.0), (3.0, 0.5))]
    line, = _earlier_gap_line(gaps, epoch)
    assert "a burn of 12 m/s there" in line and line.count("2026-01-") == 2
    assert _earlier_gap_line([], epoch) == []
    blind = [GapSensitivity(a, a + 0.5, np.inf, a + 0.4, np.zeros(3)) for a in (4.0, 5.0)]
    assert "a burn of any size there" in _earlier_gap_line(gaps + blind[:1], epoch)[0]
    assert "2 of the 5 earlier gaps could hide a burn of any size" in _earlier_gap_line(gaps + blind, epoch)[0]
