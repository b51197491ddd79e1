"""The run view's frame: radial / along-track / cross-track axes about the estimate, scaled to the cloud.

The recorder logs the particles and ellipsoids once, in km in the scene frame (``world``), and a
transform at ``world/estimate_frame`` that carries this frame's coordinates into the scene:

    p_scene_km = mean_km + R @ (units_km * q)

with ``R`` (3, 3) the unit radial, along-track and cross-track axes as columns, ``units_km`` (3,)
the length of one unit along each axis and ``q`` the coordinates in the frame. A view with its
origin at that entity shows every scene point ``p`` at ``q = (R.T @ (p - mean_km)) / units_km``:
the cloud centred on the estimate and about one unit across at every time, from an IOD cloud of
10^5 km to a converged one of a few km, so a fixed camera keeps it filling the view. Each axis
gets its own unit, the cloud's reach along it: an angles-only cloud is a needle along the line of
sight (an IOD cloud 47,000 km long and 300 km wide), which drawn to scale hides its clusters and
ellipsoids in a line; drawn per axis it shows them, and the view labels each axis with its reach
in km ("radial ±47,551 km", "along-track ±353 km"). No unit is less than 1/:data:`MAX_ASPECT`
of the largest (a flat cloud is not blown up from rounding noise).

Pure numpy; the recorder turns these arrays into rerun archetypes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CLOUD_QUANTILE", "MAX_ASPECT", "MIN_UNIT_KM", "ric_axes", "cloud_units_km", "to_frame",
           "line_through_frame", "path_through_frame", "scale_label", "screen_plane_points"]

CLOUD_QUANTILE = 0.98
"""One unit along an axis is this quantile of the particles' distances from the estimate along
it (a few stray particles do not shrink the rest of the cloud to a dot)."""

MAX_ASPECT = 1000.0
"""Largest ratio of the frame's units: a cloud thinner than this is drawn this much thinner."""

MIN_UNIT_KM = 1e-3
"""Smallest unit of the frame, km (a cloud collapsed to one point still gets a finite frame)."""


def ric_axes(position_km: np.ndarray, velocity: np.ndarray, center_km: np.ndarray) -> np.ndarray:
    """Radial, along-track and cross-track unit vectors about ``center_km`` (the Earth).

    Parameters
    ----------
    position_km : (3,) float, the estimate's position, km, scene frame
    velocity : (3,) float, the estimate's velocity in the scene frame (any unit)
    center_km : (3,) float, the centre the radial direction points away from, km

    Returns
    -------
    (3, 3) float
        A proper rotation whose columns are radial (from the centre through the estimate),
        along-track (completing the triad, along the velocity's part normal to radial) and
        cross-track (along r x v). A velocity parallel to radial (or zero) takes the scene's z
        axis (or x) for the orbit normal.
    """
    r = np.asarray(position_km, dtype=float).reshape(3) - np.asarray(center_km, dtype=float).reshape(3)
    v = np.asarray(velocity, dtype=float).reshape(3)
    rn = np.linalg.norm(r)
    radial = r / rn if rn > 0 else np.array([1.0, 0.0, 0.0])
    normal = np.cross(radial, v)
    if np.linalg.norm(normal) <= 1e-12 * max(np.linalg.norm(v), 1e-300):
        for axis in (np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])):
            normal = axis - (axis @ radial) * radial
            if np.linalg.norm(normal) > 1e-6:
                break
    cross = normal / np.linalg.norm(normal)
    along = np.cross(cross, radial)
    return np.column_stack([radial, along, cross])


def cloud_units_km(offsets_km: np.ndarray, covariance_km2: np.ndarray | None = None) -> np.ndarray:
    """The frame's unit along each of its axes, km: how far the cloud reaches from the estimate.

    Parameters
    ----------
    offsets_km : (N, 3) float, particles minus the estimate along the frame's axes, km
    covariance_km2 : (3, 3) float or None, the belief's position covariance along the frame's
        axes, km^2, used when the particles give no extent (none, or all on the estimate):
        3 times its sigma along each axis

    Returns
    -------
    (3,) float
        The :data:`CLOUD_QUANTILE` quantile of the particles' distances along each axis, raised
        to at least 1/:data:`MAX_ASPECT` of the largest and to :data:`MIN_UNIT_KM`.
    """
    d = np.abs(np.asarray(offsets_km, dtype=float).reshape(-1, 3))
    d = d[np.all(np.isfinite(d), axis=1)]
    units = np.quantile(d, CLOUD_QUANTILE, axis=0) if d.shape[0] else np.zeros(3)
    if units.max() <= MIN_UNIT_KM and covariance_km2 is not None:
        units = 3.0 * np.sqrt(np.maximum(np.diag(np.asarray(covariance_km2, dtype=float)), 0.0))
    units = np.where(np.isfinite(units), units, 0.0)
    return np.maximum(units, max(float(units.max()) / MAX_ASPECT, MIN_UNIT_KM))


def to_frame(points_km: np.ndarray, mean_km: np.ndarray, axes: np.ndarray, units_km: np.ndarray) -> np.ndarray:
    """Scene points (N, 3) km in the frame's coordinates (N, 3): ``(R.T @ (p - mean)) / units``
    (what a view with its origin at the frame shows)."""
    p = np.asarray(points_km, dtype=float).reshape(-1, 3) - np.asarray(mean_km, dtype=float).reshape(3)
    return (p @ np.asarray(axes, dtype=float)) / np.asarray(units_km, dtype=float).reshape(3)


def line_through_frame(a_km: np.ndarray, b_km: np.ndarray, mean_km: np.ndarray, axes: np.ndarray,
                       units_km: np.ndarray, half_length: float = 2.5) -> np.ndarray:
    """The part of the line through scene points ``a_km``, ``b_km`` (3,) nearest the estimate, in
    the frame's coordinates: (2, 3), ``half_length`` frame units either side of the line's point
    closest to the estimate (a line reaching to the observer would pass the camera and fill the
    view)."""
    a, b = np.asarray(a_km, dtype=float), np.asarray(b_km, dtype=float)
    d = (b - a) / np.linalg.norm(b - a)
    closest = a + ((np.asarray(mean_km, dtype=float) - a) @ d) * d
    per_km = np.linalg.norm((d @ np.asarray(axes, dtype=float)) / np.asarray(units_km, dtype=float))
    ends = closest + np.outer([-half_length, half_length], d) / per_km
    return to_frame(ends, mean_km, axes, units_km)


def scale_label(scale_km: float) -> str:
    """``scale_km`` as a short length: "384,400 km", "1,250 km", "12.5 km", "0.125 km"."""
    s = float(scale_km)
    if s >= 100.0:
        return f"{s:,.0f} km"
    return f"{s:.3g} km"


def screen_plane_points(eye: np.ndarray, right_up: np.ndarray) -> np.ndarray:
    """Points (N, 3) of the frame that a camera at ``eye`` (3,), looking at the origin with the
    frame's z axis up, sees at ``right_up`` (N, 2): offsets to the right and up on the screen, in
    frame units, in the plane through the origin facing the camera (labels placed there keep
    their place on the screen while the frame follows the cloud)."""
    e = np.asarray(eye, dtype=float).reshape(3)
    forward = -e / np.linalg.norm(e)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    ru = np.asarray(right_up, dtype=float).reshape(-1, 2)
    return ru[:, :1] * right + ru[:, 1:] * up


def path_through_frame(path_km: np.ndarray, mean_km: np.ndarray, axes: np.ndarray, units_km: np.ndarray,
                       reach: float = 3.0, centre: int | None = None) -> np.ndarray:
    """The part of a path near the estimate, in the frame's coordinates (M, 3), M = 0 when no
    point of it comes within ``reach`` frame units (along every axis) of the estimate.

    ``path_km`` (N, 3): points along the path in time order, km. The part is the run of
    consecutive points within ``reach`` about the point ``centre`` (an index; None: the point
    nearest to the estimate in frame units),
    extended on each side to where the path leaves the box of half-side ``reach``: the path seen
    where the cloud is, never its far parts, whose frame coordinates (the Moon's distance over a
    unit of a few km, 10^5 units) would streak across the view."""
    q = to_frame(path_km, mean_km, axes, units_km)
    size = np.max(np.abs(q), axis=1)
    centre = int(np.argmin(size)) if centre is None else int(centre)
    if not size[centre] <= reach:
        return np.zeros((0, 3))
    lo, hi = centre, centre
    while lo > 0 and size[lo - 1] <= reach:
        lo -= 1
    while hi < len(q) - 1 and size[hi + 1] <= reach:
        hi += 1
    part = [q[lo:hi + 1]]
    if lo > 0:
        part.insert(0, _to_box(q[lo], q[lo - 1], reach)[None])
    if hi < len(q) - 1:
        part.append(_to_box(q[hi], q[hi + 1], reach)[None])
    return np.concatenate(part)


def _to_box(inside: np.ndarray, outside: np.ndarray, reach: float) -> np.ndarray:
    """Where the segment from ``inside`` (within the box of half-side ``reach``) to ``outside``
    leaves the box (3,)."""
    d = outside - inside
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d != 0, (np.sign(d) * reach - inside) / d, np.inf)
    return inside + min(1.0, float(np.min(t))) * d
