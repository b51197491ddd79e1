"""What the rerun viewer shows at first open: the blueprint (views, their contents, camera).

Plain data for :mod:`.rerun_recorder`, which hands it to every recording it opens.
"""
from __future__ import annotations

import numpy as np

from cistrack.lazy import LazyModule

rrb = LazyModule("rerun.blueprint")  # loads with the first recording, not with the registry

__all__ = ["SIGMA_ENTITIES", "TIMELINES", "camera_for", "default_blueprint"]


SIGMA_ENTITIES = ("sigma_x_km", "sigma_y_km", "sigma_z_km", "sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms")
"""Per-axis 1-sigma metrics, logged at ``metrics/<name>`` (rerun queries take no wildcards)."""

TIMELINES = ("utc", "step", "event")


def _whole_run() -> list:
    """Visible time ranges covering the whole run on every timeline (not a window at the cursor)."""
    every = rrb.TimeRangeBoundary.infinite()
    return [rrb.VisibleTimeRange(t, start=every, end=every) for t in TIMELINES]


def _whole_axis():
    """An x axis that opens on the whole run (the viewer's default is a window at the cursor)."""
    every = rrb.TimeRangeBoundary.infinite()
    return rrb.TimeAxis(view_range=rrb.TimeRange(start=every, end=every))


def _series(name: str, entities: list[str] | None, origin: str = "metrics",
            y_range: tuple[float, float] | None = None):
    contents = [f"$origin/{e}" for e in entities] if entities else "$origin/**"
    return rrb.TimeSeriesView(origin=origin, name=name, contents=contents, time_ranges=_whole_run(),
                              axis_x=_whole_axis(),
                              axis_y=rrb.ScalarAxis(range=y_range) if y_range is not None else None)


def camera_for(points_km: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
    """(eye position, look target), km: looking at the box around ``points_km`` (N, 3) from
    above and to the side, far enough to see all of it; None without points."""
    if points_km is None:
        return None
    pts = np.asarray(points_km, dtype=float).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if pts.shape[0] == 0:
        return None
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = 0.5 * (lo + hi)
    size = max(float(np.max(hi - lo)), 2.0e4)  # at least 20,000 km across
    direction = np.array([0.55, -0.65, 0.52])
    return target + 1.6 * size * direction / np.linalg.norm(direction), target


def default_blueprint(focus_km: np.ndarray | None = None) -> rrb.Blueprint:
    """What the viewer shows at first open.

    Left, the run: a 3-D view framed on ``focus_km`` (N, 3) points, the truth trajectory and the
    initial cloud (particles, ellipsoids, estimate, truth); below it the whole Earth–Moon system
    with the libration points. Right, time series over the whole run: estimation error, per-axis
    1-sigma of position and of velocity (the ``metrics/sigma_*`` entities), entropy, NEES and component weights.
    """
    eye = camera_for(focus_km)
    controls = (rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=eye[0], look_target=eye[1],
                                  eye_up=(0.0, 0.0, 1.0)) if eye is not None else None)
    run_view = rrb.Spatial3DView(origin="world", name="Run: truth, cloud and ellipsoids (synodic, km)",
                                 eye_controls=controls, background=rrb.BackgroundKind.GradientDark)
    system = rrb.Spatial3DView(origin="world", name="Earth–Moon system (synodic, km)",
                               contents=["$origin/earth", "$origin/moon", "$origin/libration",
                                         "$origin/truth/**", "$origin/estimate", "$origin/observer"],
                               background=rrb.BackgroundKind.GradientDark)
    series = rrb.Vertical(
        _series("Estimation error (km, m/s)", ["pos_err_km", "vel_err_ms"]),
        _series("1-sigma per axis, position (km)", list(SIGMA_ENTITIES[:3])),
        _series("1-sigma per axis, velocity (cm/s)", list(SIGMA_ENTITIES[3:])),
        _series("Entropy (nats)", ["entropy"]),
        _series("NEES (6 = consistent; 90 % of a consistent filter's values lie in 1.6-12.6)", ["nees"],
                y_range=(0.0, 20.0)),
        _series("Component weights", None, origin="components"),
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(run_view, system, row_shares=[3, 2]),
            series,
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline="utc", state="collapsed"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )
