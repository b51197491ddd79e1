"""The truth trajectory in the run view: only its part near the estimate, in the estimate frame,
one UI point wide (the whole trajectory, drawn through a frame a few km across, is a band of
huge coordinates across the view)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.recorders.blueprint import RUN_VIEW_CONTENTS
from cistrack.plugins.recorders.estimate_frame import path_through_frame, to_frame
from cistrack.plugins.recorders.run_view_log import TRUTH_PATH, truth_path_in_frame

from .rrd_reading import component, read_entities


@pytest.fixture(scope="module")
def entities(recorded_run):
    return read_entities(recorded_run.full_rrd)


def _by_event(rows):
    return {r.times["event"]: r for r in rows if "event" in r.times}


def _frame(row):
    """(mean (3,) km, axes (3, 3), units (3,) km) of a logged frame transform (axes @ diag(units),
    stored column by column)."""
    mat = component(row, "Transform3D:mat3x3").reshape(3, 3).T
    units = np.linalg.norm(mat, axis=0)
    return component(row, "Transform3D:translation").reshape(3), mat / units, units


def _distance_to_polyline(p: np.ndarray, line: np.ndarray) -> float:
    a, b = line[:-1], line[1:]
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def test_the_run_view_shows_the_truth_path_in_the_frame_not_the_whole_trajectory():
    assert "/world/truth/trajectory" not in RUN_VIEW_CONTENTS
    assert any(TRUTH_PATH.startswith(c.strip("/").rstrip("*")) for c in RUN_VIEW_CONTENTS if c.endswith("**"))


def test_the_truth_path_stays_near_the_estimate_and_passes_through_the_truth(entities):
    frames = _by_event(entities["/world/estimate_frame"])
    truths = _by_event(entities["/world/truth/position"])
    paths = _by_event(entities[f"/{TRUTH_PATH}"])
    assert len(paths) == len(truths)
    for event, row in paths.items():
        mean, axes, units = _frame(frames[event])
        truth = to_frame(component(truths[event], "Points3D:positions"), mean, axes, units)[0]
        if np.abs(truth).max() > 3.0:  # the truth outside the cloud's box: no path
            assert "Clear:is_recursive" in row.components
            continue
        line = np.asarray(row.components["LineStrips3D:strips"][0], dtype=float)
        assert np.abs(line).max() <= 3.0 + 1e-6  # frame units: never the far trajectory
        assert _distance_to_polyline(truth, line) < 1e-3


def test_the_truth_path_is_one_ui_point_wide(entities):
    rows = [r for r in entities[f"/{TRUTH_PATH}"] if "LineStrips3D:radii" in r.components]
    assert rows
    for row in rows:
        assert np.asarray(row.components["LineStrips3D:radii"], dtype=float).tolist() == [-1.0]  # UI points


def test_a_path_is_cut_where_it_leaves_the_box_about_the_estimate():
    t = np.linspace(-10.0, 10.0, 21)
    path = np.column_stack([t * 100.0, np.zeros_like(t), np.zeros_like(t)])
    part = path_through_frame(path, np.zeros(3), np.eye(3), np.array([100.0, 1.0, 1.0]), reach=3.0)
    assert part[0, 0] == pytest.approx(-3.0) and part[-1, 0] == pytest.approx(3.0)
    assert np.abs(part).max() <= 3.0


def test_the_truth_path_passes_through_the_truth_between_samples_far_outside_the_box():
    """A converged cloud's box (units of 2 km) is smaller than the trajectory's sample spacing
    (300 km): the path is the truth now, joined to its neighbouring samples and cut at the box."""
    times = np.array([0.0, 2.0, 4.0])
    samples = np.array([[-600.0, 1.0, 0.0], [-300.0, 1.0, 0.0], [300.0, 1.0, 0.0]])
    frame = (np.zeros(3), np.eye(3), np.full(3, 2.0))
    part = truth_path_in_frame(samples, times, 3.0, np.array([0.0, 1.0, 0.0]), frame)
    np.testing.assert_allclose(part, [[-3.0, 0.5, 0.0], [0.0, 0.5, 0.0], [3.0, 0.5, 0.0]])


def test_a_path_that_misses_the_box_gives_nothing():
    path = np.array([[0.0, 50.0, 0.0], [10.0, 50.0, 0.0]])
    assert path_through_frame(path, np.zeros(3), np.eye(3), np.ones(3), reach=3.0).shape == (0, 3)
