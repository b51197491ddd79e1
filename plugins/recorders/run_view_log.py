"""Logging of what the run view and the series panels draw: the estimate frame and the plotted series.

Functions of a :class:`rerun.RecordingStream`, called by :mod:`.rerun_recorder` at each event
(the frame) and each step with metrics (the series); the numbers come from
:mod:`.estimate_frame` and :mod:`.run_series`.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import LazyModule

from .blueprint import RUN_VIEW_EYE
from .estimate_frame import cloud_units_km, path_through_frame, ric_axes, scale_label, screen_plane_points
from .run_series import NEES_BAND_ENTITIES, SERIES, log10_series, nees_band_series, rank_entity, ranked_weights

rr = LazyModule("rerun")

__all__ = ["AXIS_COLOURS", "AXIS_LABELS_AT", "AXIS_NAMES", "LEGEND", "LEGEND_AT", "LEGEND_ROWS", "ROW_STEP",
           "TRUTH_PATH", "legend_lines", "log_estimate_frame", "log_legend", "log_run_view_styles", "log_series",
           "log_truth_path", "truth_path_in_frame"]

AXIS_NAMES = ("radial", "along-track", "cross-track")
AXIS_COLOURS = [(255, 90, 90), (120, 220, 120), (110, 150, 255)]
"""RGB of the radial, along-track and cross-track arrows (their labels a lighter shade)."""

LEGEND = "world/estimate_frame/legend"
"""The run view's legend of the mixture components: a labelled dot in each one's colour."""

LEGEND_AT = (-2.75, 1.55)
"""Screen place of the legend's first row in the run view (right, up; frame units in the plane
through the estimate facing the camera :data:`.blueprint.RUN_VIEW_EYE`): its top-left corner,
clear of the cloud (within about 1.5 units of the centre on the screen)."""

AXIS_LABELS_AT = (-2.75, -1.25)
"""Screen place of the first of the three axis labels (bottom-left corner of the run view); each
label is in its arrow's colour and names the axis and its reach in km."""

ROW_STEP = 0.24
"""Screen distance between two rows of the legend or the axis labels, frame units (one line)."""

TRUTH_PATH = "world/estimate_frame/truth_path"
"""The truth trajectory near the estimate, in the run view's frame (the whole trajectory, drawn
through a frame a few km across, would streak across the view as a band)."""

LEGEND_ROWS = 8
"""Components listed in the legend at most: the heaviest ones."""


def log_run_view_styles(rec: rr.RecordingStream) -> None:
    """Static parts: the frame's view coordinates and the colour and name of every series line."""
    rec.log("world/estimate_frame", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for s in SERIES:
        rec.log(s.entity, rr.SeriesLines(colors=[s.color], names=[s.label], widths=[2.0]), static=True)
    for entity, name in zip(NEES_BAND_ENTITIES, ("5 %", "95 %")):
        rec.log(entity, rr.SeriesLines(colors=[(150, 150, 150)], names=[name], widths=[1.5]), static=True)


def log_estimate_frame(rec: rr.RecordingStream, mean_km: np.ndarray, velocity: np.ndarray,
                       cloud_km: np.ndarray, covariance_km2: np.ndarray,
                       earth_km: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The run view's frame at this event and its labelled axes.

    Parameters
    ----------
    mean_km : (3,) the estimate, km; velocity : (3,) its velocity (any unit), scene frame
    cloud_km : (N, 3) the logged particles, km
    covariance_km2 : (3, 3) the belief's position covariance, km^2 (when the particles give no extent)
    earth_km : (3,) the Earth's centre, km (the radial axis points away from it)

    Returns
    -------
    axes : (3, 3) radial, along-track, cross-track unit vectors as columns
    units : (3,) km per frame unit along each axis (the cloud's reach along it)
    """
    axes = ric_axes(mean_km, velocity, earth_km)
    units = cloud_units_km((np.asarray(cloud_km) - mean_km) @ axes, axes.T @ covariance_km2 @ axes)
    rec.log("world/estimate_frame", rr.Transform3D(translation=mean_km, mat3x3=axes * units[None, :]))
    rec.log("world/estimate_frame/axes", rr.Arrows3D(
        vectors=np.eye(3), colors=AXIS_COLOURS, radii=rr.Radius.ui_points(1.5), show_labels=False))
    rec.log("world/estimate_frame/axis_labels", rr.Points3D(
        _rows(AXIS_LABELS_AT, 3), colors=[tuple(128 + c // 2 for c in col) for col in AXIS_COLOURS],
        labels=[f"{name} ±{scale_label(u)}" for name, u in zip(AXIS_NAMES, units)],
        radii=rr.Radius.ui_points(2.0), show_labels=True))
    return axes, units


def _rows(first: tuple[float, float], n: int) -> np.ndarray:
    """Frame points (n, 3) that the run view's camera shows as a column of ``n`` rows from
    ``first`` (right, up) downwards, :data:`ROW_STEP` apart."""
    right_up = np.column_stack([np.full(n, first[0]), first[1] - ROW_STEP * np.arange(n)])
    return screen_plane_points(np.asarray(RUN_VIEW_EYE, dtype=float), right_up)


def legend_lines(weights: np.ndarray) -> list[tuple[int, str]]:
    """(component, text) of the legend's rows: the :data:`LEGEND_ROWS` heaviest components of
    ``weights`` (M,), heaviest first ("component 2: w 0.412"); a last row counts the others."""
    w = np.asarray(weights, dtype=float).reshape(-1)
    order = np.argsort(-w, kind="stable")
    rows = [(int(i), f"component {int(i)}: w {w[i]:.3f}") for i in order[:LEGEND_ROWS]]
    if w.size > LEGEND_ROWS:
        rows.append((int(order[LEGEND_ROWS]), f"+ {w.size - LEGEND_ROWS} lighter components"))
    return rows


def log_legend(rec: rr.RecordingStream, weights: np.ndarray) -> None:
    """The run view's legend at this event: a dot and a label in each component's colour (its
    class id in the recording's annotation context) with its weight (:func:`legend_lines`)."""
    rows = legend_lines(weights)
    rec.log(LEGEND, rr.Points3D(_rows(LEGEND_AT, len(rows)), class_ids=[i for i, _ in rows],
                                labels=[text for _, text in rows], radii=rr.Radius.ui_points(4.0),
                                show_labels=True))


def truth_path_in_frame(truth_km: np.ndarray, truth_t: np.ndarray, t: float, at_km: np.ndarray,
                        frame: tuple) -> np.ndarray:
    """The truth trajectory where it passes the estimate at time ``t``, in the frame (M, 3).

    ``truth_km`` (N, 3) km at times ``truth_t`` (N,): the dense truth; ``at_km`` (3,): the truth
    at ``t``, put into the trajectory between its samples (they lie minutes apart, hundreds of km,
    more than a converged cloud's box); ``frame`` = (mean (3,) km, axes, units) of
    :func:`log_estimate_frame`. The part about ``at_km`` within the box of
    :func:`.estimate_frame.path_through_frame`; (0, 3) when the truth is outside it."""
    mean, axes, units = frame
    i = int(np.searchsorted(truth_t, t))
    path = np.insert(np.asarray(truth_km, dtype=float), i, np.asarray(at_km, dtype=float).reshape(3), axis=0)
    return path_through_frame(path, mean, axes, units, centre=i)


def log_truth_path(rec: rr.RecordingStream, part: np.ndarray) -> None:
    """The truth near the estimate, ``part`` (M, 3) frame units of :func:`truth_path_in_frame`,
    one UI point wide; cleared when there is none."""
    if part.shape[0] < 2:
        rec.log(TRUTH_PATH, rr.Clear(recursive=False))
        return
    rec.log(TRUTH_PATH, rr.LineStrips3D([part], colors=[(230, 230, 230)], radii=rr.Radius.ui_points(1.0)))


def log_series(rec: rr.RecordingStream, metrics: dict, weights: np.ndarray, n_ranks: int) -> int:
    """The plotted series of a step with metrics: log10 errors and sigmas, the NEES band, the
    ``weights`` (M,) ranked. ``n_ranks``: ranks logged so far (a new rank gets its line style);
    returns the ranks logged now."""
    for entity, value in {**log10_series(metrics), **nees_band_series()}.items():
        rec.log(entity, rr.Scalars(value))
    ranked = ranked_weights(weights, n_ranks)
    for k in range(n_ranks, ranked.size):  # a rank seen for the first time: its style
        shade = int(255 - 150 * min(k, 5) / 5)
        rec.log(rank_entity(k + 1), rr.SeriesLines(colors=[(shade, shade, 90 + shade // 3)],
                                                   names=[_ordinal(k + 1)], widths=[2.0]), static=True)
    for k, w in enumerate(ranked):
        rec.log(rank_entity(k + 1), rr.Scalars(float(w)))
    return int(ranked.size)


def _ordinal(k: int) -> str:
    """1 -> "largest", 2 -> "2nd", 3 -> "3rd", 4 -> "4th", 11 -> "11th"."""
    if k == 1:
        return "largest"
    return f"{k}{ {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10 if k % 100 not in (11, 12, 13) else 0, 'th')}"
