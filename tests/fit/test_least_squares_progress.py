"""A long least squares says its iterations to whoever watches (cistrack.least_squares.progress):
66,000 observations had left ``cistrack fit`` silent for 201 s. A linear problem (a free particle
whose position is measured) started off its minimum, with the threshold lowered to 10 rows."""
from __future__ import annotations

import numpy as np
import pytest

from .linear_components import FreeParticle, PositionSensor
from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.line_of_variations import line_of_variations
from cistrack.least_squares import progress
from cistrack.least_squares.progress import reported_to

X0 = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])


def _fit(n: int):
    """(sensor, measurements, fit) of ``n`` positions over 2 time units."""
    times = np.linspace(0.0, 2.0, n)
    sen = PositionSensor(sigma=1e-6)
    states = np.array([np.concatenate([X0[:3] + X0[3:] * t, X0[3:]]) for t in times])
    ms = sen.simulate(states, times, np.random.default_rng(0))
    return sen, ms, fit_orbit(FreeParticle(), sen, ms, X0 + np.array([1e-3, 0, 0, 0, 1e-4, 0]), 0.0)


@pytest.fixture
def ten_rows(monkeypatch):
    monkeypatch.setattr(progress, "PROGRESS_ROWS", 10)


def test_a_least_squares_over_the_threshold_says_its_iterations(ten_rows):
    said: list[str] = []
    with reported_to(said.append):
        _fit(12)
    assert said and all(line.startswith("    least squares") for line in said)
    assert any("iteration" in line and "chi-square" in line and "over 12 observations" in line for line in said)


def test_a_shorter_one_says_nothing(ten_rows):
    said: list[str] = []
    with reported_to(said.append):
        _fit(8)
    assert said == []


def test_outside_reported_to_nothing_is_said(ten_rows, capsys):
    _fit(12)
    assert capsys.readouterr() == ("", "")


def test_a_long_line_of_variations_says_each_point_not_each_iteration(ten_rows):
    sen, ms, fit = _fit(12)
    said: list[str] = []
    with reported_to(said.append):
        points = line_of_variations(FreeParticle(), sen, ms, fit, step=1.0, max_sigma=2.0,
                                    options=FitOptions(reject_outliers=False))
    assert len(points) == 5
    assert len(said) == 4 and all(line.startswith("    line of variations at ") for line in said)
    assert {line.split(" at ")[1].split(" sigma")[0] for line in said} == {"+1", "+2", "-1", "-2"}
