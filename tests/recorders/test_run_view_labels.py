"""Where the run view's labels are drawn: the axis labels and the legend of the mixture
components stand beside the cloud on the screen, never on it.

Seen from the run view's fixed camera (:data:`RUN_VIEW_EYE`, looking at the estimate with the
frame's z axis up), the cloud lies within one unit of the estimate along each axis; its screen
area is at most that of the cube [-1, 1]^3. Positions are read back from a recorded run and
projected with that camera.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from cistrack.plugins.recorders.blueprint import RUN_VIEW_EYE
from cistrack.plugins.recorders.run_view_log import LEGEND, LEGEND_ROWS, legend_lines

from .rrd_reading import component, read_entities


def project(points: np.ndarray) -> np.ndarray:
    """Screen coordinates (N, 2), right and up, of frame points (N, 3) seen from RUN_VIEW_EYE."""
    eye = np.asarray(RUN_VIEW_EYE, dtype=float)
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = np.asarray(points, dtype=float).reshape(-1, 3) - eye
    depth = d @ forward
    return np.column_stack([d @ right / depth, d @ up / depth])


CLOUD_BOX = project(np.array(list(itertools.product([-1.0, 1.0], repeat=3))))
"""The screen's corners of the cube of one unit about the estimate (8, 2)."""


def outside_cloud(points: np.ndarray) -> np.ndarray:
    """Whether each frame point (N, 3) shows outside the screen box around the cloud's cube."""
    s = project(points)
    lo, hi = CLOUD_BOX.min(axis=0), CLOUD_BOX.max(axis=0)
    return np.any((s < lo) | (s > hi), axis=1)


@pytest.fixture(scope="module")
def entities(recorded_run):
    return read_entities(recorded_run.full_rrd)


def test_axis_labels_are_drawn_beside_the_cloud_on_the_screen(entities):
    rows = [r for r in entities["/world/estimate_frame/axis_labels"] if r.times]
    assert rows
    for row in rows:
        assert outside_cloud(component(row, "Points3D:positions")).all()


def test_the_legend_is_drawn_beside_the_cloud_on_the_screen(entities):
    rows = [r for r in entities[f"/{LEGEND}"] if r.times]
    assert rows
    for row in rows:
        assert outside_cloud(component(row, "Points3D:positions")).all()


def test_the_legend_names_every_component_in_its_colour_with_its_weight(entities, recorded_run):
    legend = sorted((r for r in entities[f"/{LEGEND}"] if r.times), key=lambda r: r.times["event"])
    assert len(legend) == len(recorded_run.log.events)
    for row, ev in zip(legend, recorded_run.log.events):
        ids = [int(i) for i in row.components["Points3D:class_ids"]]  # colour = the particles' class
        texts = row.components["Points3D:labels"]
        assert sorted(ids) == list(range(len(ev.weights)))
        for i, text in zip(ids, texts):
            assert text == f"component {i}: w {ev.weights[i]:.3f}"
        assert [ev.weights[i] for i in ids] == sorted(ev.weights, reverse=True)  # heaviest first


def test_a_long_legend_lists_the_heaviest_components_and_counts_the_rest():
    w = np.linspace(1.0, 2.0, LEGEND_ROWS + 3)
    rows = legend_lines(w / w.sum())
    assert [i for i, _ in rows[:LEGEND_ROWS]] == list(range(LEGEND_ROWS + 2, 2, -1))
    assert rows[-1][1] == "+ 3 lighter components"
