"""Logging of what the run view and the series panels draw: the estimate frame and the plotted series.

Functions of a :class:`rerun.RecordingStream`, called by :mod:`.rerun_recorder` at each event
(the frame) and each step with metrics (the series); the numbers come from
:mod:`.estimate_frame` and :mod:`.run_series`.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import LazyModule

from .estimate_frame import cloud_units_km, ric_axes, scale_label
from .run_series import NEES_BAND_ENTITIES, SERIES, log10_series, nees_band_series, rank_entity, ranked_weights

rr = LazyModule("rerun")

__all__ = ["AXIS_COLOURS", "AXIS_LABEL_AT", "AXIS_NAMES", "log_estimate_frame", "log_run_view_styles",
           "log_series"]

AXIS_NAMES = ("radial", "along-track", "cross-track")
AXIS_COLOURS = [(255, 90, 90), (120, 220, 120), (110, 150, 255)]
"""RGB of the radial, along-track and cross-track arrows (their labels a lighter shade)."""

AXIS_LABEL_AT = 1.25
"""Where the run view's axis labels sit on each axis, in frame units: past the arrow's tip (one
unit) and the cloud (most of it lies within one unit), so the cloud does not cover them."""


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
        AXIS_LABEL_AT * np.eye(3), colors=[tuple(128 + c // 2 for c in col) for col in AXIS_COLOURS],
        labels=[f"{name} ±{scale_label(u)}" for name, u in zip(AXIS_NAMES, units)],
        radii=rr.Radius.ui_points(2.0), show_labels=True))
    return axes, units


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
