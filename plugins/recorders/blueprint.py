"""What the rerun viewer shows at first open: the blueprint (views, their contents, cameras, playback).

Plain data for :mod:`.rerun_recorder`, which hands it to every recording it opens.

Left, two 3-D views. Top, the run about the estimate: its origin is ``world/estimate_frame``
(see :mod:`.estimate_frame`), a frame that follows the estimate and scales with the cloud, so the
fixed camera :data:`RUN_VIEW_EYE` keeps the cloud and its ellipsoids filling the view from the IOD
to convergence. Bottom, the Earth–Moon system seen from above, from the Earth to beyond L2. Right,
time series over the whole run in log10 (see :mod:`.run_series`), their colours named in the
titles instead of legends over the data, and the time panel set so that playing the run takes
about :data:`PLAYBACK_S` seconds in a viewer that keeps up, or (``frame_s``) in one that draws a
frame every ``frame_s`` seconds, such as a web viewer on a software renderer
(:data:`SOFTWARE_FRAME_S`; ``cistrack view`` serves that variant to such a browser, see
:mod:`.web_viewer`).
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import LazyModule

from .maneuver_marks import (DETECTIONS, ESTIMATED_BURNS, NEES_BURNS, NEES_DETECTIONS, STATISTIC,
                             STATISTIC_BURNS, THRESHOLD)
from .run_series import NEES_BAND, NEES_BAND_ENTITIES, SERIES, nees_y_range

rrb = LazyModule("rerun.blueprint")  # loads with the first recording, not with the registry

__all__ = ["APPLICATION_ID", "FRAME_CAP_S", "PLAYBACK_S", "RUN_VIEW_EYE", "SOFTWARE_FRAME_S", "TIMELINES",
           "axis_range_s", "camera_for", "points_box", "default_blueprint", "playback_speed"]


APPLICATION_ID = "cistrack"
"""The rerun application id of cistrack's recordings; a blueprint applies to recordings of its id."""

TIMELINES = ("utc", "step", "event")

PLAYBACK_S = 60.0
"""Seconds that playing a whole run takes at the speed the time panel opens with, in a viewer that
draws at least 10 frames a second. Rerun (0.41) moves the time cursor by the speed times a frame's
duration, that duration capped at 0.1 s, so a slower viewer plays slower in proportion: headless
Chromium without a GPU (software rasterizer, about 1.5 s a frame on 2 busy cores) played Example 1
about 15 times slower (docs/viewer.md). The speed is a property of the recording, not of the
machine that shows it, so the recording's own is set for a viewer that keeps up; ``cistrack view``
gives a browser that renders in software a second one, set for :data:`SOFTWARE_FRAME_S`."""

FRAME_CAP_S = 0.1
"""The most of a frame's duration by which rerun (0.41) moves the time cursor while playing."""

SOFTWARE_FRAME_S = 1.5
"""Seconds per frame of the web viewer on a software renderer (headless Chromium with SwiftShader,
Example 1's recording, 1600 x 1000 page, 2 shared cores: 1.5 to 2 s; docs/viewer.md)."""

RUN_VIEW_EYE = (1.8, -3.0, 1.7)
"""Camera of the run view in the estimate frame (units of the cloud's extent): from the radial,
negative along-track, cross-track side, far enough to see the cloud (most of it within one unit)
and most of its 3-sigma ellipsoids."""

RUN_VIEW_CONTENTS = ("/world/particles", "/world/components", "/world/estimate", "/world/truth/position",
                     "/world/estimate_frame/**")
"""What the run view draws: the cloud and the estimate, the truth, and in the estimate frame its axes,
labels, legend, line of sight and the truth trajectory near the estimate (the whole trajectory is
the system view's)."""
SYSTEM_VIEW_CONTENTS = ("/world/earth", "/world/moon", "/world/libration", "/world/truth/**",
                        "/world/estimate", "/world/observer", "/world/particles", "/world/line_of_sight",
                        "/world/observers/**")


def _whole_run() -> list:
    """Visible time ranges covering the whole run on every timeline (not a window at the cursor)."""
    every = rrb.TimeRangeBoundary.infinite()
    return [rrb.VisibleTimeRange(t, start=every, end=every) for t in TIMELINES]


AXIS_MARGIN = 0.07
"""Fraction of a series panel's width kept free of day and half-day ticks at either end: a date
label centred on a tick closer to an edge would be cut by the panel ("6-01-02")."""

_HALF_DAY_S = 43_200.0


def axis_range_s(start: float, end: float) -> tuple[float, float]:
    """The x range (unix seconds) that shows ``start`` .. ``end`` with no day or half-day tick
    within :data:`AXIS_MARGIN` of an end (each end moves outwards past such a tick); a run of
    more than four days is padded by that margin on both sides."""
    lo, hi = float(start), float(end)
    if hi - lo > 8 * _HALF_DAY_S:  # ticks farther apart than half days: pad both ends instead
        pad = AXIS_MARGIN * (hi - lo)
        return lo - pad, hi + pad
    for _ in range(4):  # widening moves the other margin; a few rounds settle it
        m = AXIS_MARGIN * (hi - lo)
        first = np.ceil(lo / _HALF_DAY_S) * _HALF_DAY_S
        if first < lo + m:
            lo = first - m / (1.0 - AXIS_MARGIN)
        last = np.floor(hi / _HALF_DAY_S) * _HALF_DAY_S
        if last > hi - m:
            hi = last + m / (1.0 - AXIS_MARGIN)
    return lo, hi


def _whole_axis(utc_range_s: tuple[float, float] | None = None):
    """An x axis that opens on the whole run (the viewer's default is a window at the cursor):
    ``utc_range_s`` (unix seconds) widened by :func:`axis_range_s`, else every time there is."""
    if utc_range_s is None or not utc_range_s[1] > utc_range_s[0]:
        every = rrb.TimeRangeBoundary.infinite()
        return rrb.TimeAxis(view_range=rrb.TimeRange(start=every, end=every))
    lo, hi = axis_range_s(*utc_range_s)
    return rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.absolute(seconds=lo),
                                                 end=rrb.TimeRangeBoundary.absolute(seconds=hi)))


def _series(name: str, entities: list[str], utc_range_s: tuple[float, float] | None,
            y_range: tuple[float, float] | None = None):
    """A time-series panel of ``entities``. No legend: a legend box covers some curve wherever it
    sits, so each title names its curves' colours (see :mod:`.run_series`)."""
    return rrb.TimeSeriesView(origin="/", name=name, contents=[f"/{e}" for e in entities],
                              time_ranges=_whole_run(), axis_x=_whole_axis(utc_range_s),
                              axis_y=rrb.ScalarAxis(range=y_range) if y_range is not None else None,
                              plot_legend=rrb.PlotLegend(visible=False))


def points_box(points_km: np.ndarray | None) -> np.ndarray | None:
    """(2, 3) the corners (min, max) of the box around the finite rows of ``points_km`` (N, 3);
    None without any. The system view's camera (:func:`camera_for`) depends on this box only."""
    if points_km is None:
        return None
    pts = np.asarray(points_km, dtype=float).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    return np.stack([pts.min(axis=0), pts.max(axis=0)]) if pts.shape[0] else None


def camera_for(points_km: np.ndarray | None, direction=(0.55, -0.65, 0.52),
               distance: float = 1.6) -> tuple[np.ndarray, np.ndarray] | None:
    """(eye position, look target), km: looking at the box around ``points_km`` (N, 3) along
    ``direction`` (from the target to the eye), ``distance`` times the box's largest side away;
    None without points."""
    box = points_box(points_km)
    if box is None:
        return None
    lo, hi = box
    target = 0.5 * (lo + hi)
    size = max(float(np.max(hi - lo)), 2.0e4)  # at least 20,000 km across
    d = np.asarray(direction, dtype=float)
    return target + distance * size * d / np.linalg.norm(d), target


def playback_speed(utc_range_s: tuple[float, float] | None, frame_s: float | None = None) -> float:
    """Playback multiplier that plays a run spanning ``utc_range_s`` (unix seconds, first and
    last time) in :data:`PLAYBACK_S` seconds (1 without a range) in a viewer drawing a frame every
    ``frame_s`` seconds (None: one that keeps up, at least 1 / :data:`FRAME_CAP_S` frames a
    second). A slower viewer moves the cursor by at most :data:`FRAME_CAP_S` of each frame, so
    its speed is raised by ``frame_s / FRAME_CAP_S``."""
    if utc_range_s is None:
        return 1.0
    span = float(utc_range_s[1] - utc_range_s[0])
    slowdown = max(1.0, float(frame_s) / FRAME_CAP_S) if frame_s is not None else 1.0
    return max(1.0, span * slowdown / PLAYBACK_S) if np.isfinite(span) and span > 0 else 1.0


def _eye(eye: tuple[np.ndarray, np.ndarray] | None):
    if eye is None:
        return None
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=eye[0], look_target=eye[1],
                             eye_up=(0.0, 0.0, 1.0))


def _log_columns():
    """The maneuver log's one column: the text, which says what each entry is and its time in days
    (a ``utc`` column this narrow shows "2..." only)."""
    from rerun.blueprint.archetypes import TextLogColumns
    from rerun.blueprint.encodings import TextLogColumn, TimelineColumn

    return TextLogColumns(timeline_columns=[TimelineColumn(t, visible=False) for t in TIMELINES],
                          text_log_columns=[TextLogColumn("body")])


def _series_column(r: tuple[float, float] | None, watching: bool, burns: bool):
    """The right column: the time series (:func:`default_blueprint`), with the maneuver detector's
    panel when the run ``watching`` for maneuvers and the maneuvers' text log when it has truth
    ``burns``."""
    nees_title = f"log10 NEES; grey: chi-square 90 % band ({NEES_BAND[0]:.1f} to {NEES_BAND[1]:.1f})"
    if burns:
        nees_title = (f"log10 NEES, grey: 90 % band ({NEES_BAND[0]:.1f} to {NEES_BAND[1]:.1f}); "
                      "detections red, burns orange")
    nees_extra = ([NEES_DETECTIONS] if watching else []) + ([f"{NEES_BURNS}/**"] if burns else [])
    panels = [
        _series("Position, log10 km: error red; 1-sigma x blue, y green, z orange",
                [s.entity for s in SERIES if s.panel == "position"], r),
        _series("Velocity, log10 m/s: error red; 1-sigma x blue, y green, z orange",
                [s.entity for s in SERIES if s.panel == "velocity"], r),
        _series("Entropy, nats", ["metrics/entropy"], r),
        _series(nees_title, ["series/nees/nees", *NEES_BAND_ENTITIES, *nees_extra], r, y_range=nees_y_range()),
    ]
    if watching:
        panels.append(_series(
            "Maneuver test -log10 p blue, threshold grey; "  # at most ~82 characters: longer ones are cut
            + ("detected red; burn orange, fit green" if burns else "detections red, fitted burns green"),
            [STATISTIC, THRESHOLD, DETECTIONS, ESTIMATED_BURNS, *([f"{STATISTIC_BURNS}/**"] if burns else [])], r))
    panels.append(_series("Component weights, largest first (brightest)", ["components/ranked/**"], r,
                          y_range=(0.0, 1.05)))
    if not burns:
        return rrb.Vertical(*panels)
    log = rrb.TextLogView(origin="/maneuvers", name="Maneuvers: truth burns, detections, estimates",
                          columns=_log_columns())
    return rrb.Vertical(*panels, log, row_shares=[1.0] * len(panels) + [1.4])


def default_blueprint(system_km: np.ndarray | None = None, utc_range_s: tuple[float, float] | None = None,
                      live: bool = False, watching: bool = False, burns: bool = False,
                      frame_s: float | None = None) -> rrb.Blueprint:
    """What the viewer shows at first open.

    ``system_km`` (N, 3): points the system view frames from above (Earth, Moon, L1, L2 and the
    truth trajectory); ``utc_range_s``: the run's first and last time on the ``utc`` timeline,
    unix seconds, which set the series' x axes and the playback speed (:func:`playback_speed`);
    ``live``: the run streams to a viewer (follow the newest data instead of opening paused at the
    start); ``watching``: the run's updates carry the maneuver detector's statistic (its panel
    beside the NEES); ``burns``: the truth has burns (their lines on both panels and a text log of
    the maneuvers, see :mod:`.maneuver_marks`); ``frame_s``: seconds per frame of the viewer it is
    for (:func:`playback_speed`; None: one that keeps up).
    """
    r = utc_range_s
    run_view = rrb.Spatial3DView(
        origin="/world/estimate_frame", contents=list(RUN_VIEW_CONTENTS),
        name="Run about the estimate: radial, along-track, cross-track (km: the cloud's reach per axis)",
        eye_controls=_eye((np.array(RUN_VIEW_EYE), np.zeros(3))), background=rrb.BackgroundKind.GradientDark)
    system = rrb.Spatial3DView(origin="/world", name="Earth–Moon system (synodic, km, from above)",
                               contents=list(SYSTEM_VIEW_CONTENTS),
                               eye_controls=_eye(camera_for(system_km, direction=(0.0, -0.35, 1.0),
                                                            distance=0.78)),
                               background=rrb.BackgroundKind.GradientDark)
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(run_view, system, row_shares=[3, 2]),
            _series_column(r, watching, burns),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline="utc", state="collapsed", playback_speed=playback_speed(r, frame_s),
                      play_state=None if live else "paused"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )
