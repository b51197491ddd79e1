"""Every observer of a run in the viewer: its position, the lines of sight it measured at this
step and, for a telescope in space, its exclusion cones about the Sun, Earth and Moon.

Entities (positions in the recording's frame, km)::

    world/observers/<key>                  the observer's position (key "observer" for one sensor)
    world/observers/<key>/line_of_sight    its measured lines of sight at this step (cleared otherwise)
    world/observers/<key>/exclusion/<body> the rim of each active exclusion cone, drawn at
                                           CONE_LENGTH_LU from the observer
"""
from __future__ import annotations

import numpy as np
from cistrack.lazy import LazyModule
from cistrack.units import LU_KM

from .scene import primary_positions, system_mu

rr = LazyModule("rerun")

__all__ = ["log_observers", "observers_of", "cone_rim", "CONE_LENGTH_LU", "LABEL_MIN_DISTANCE_LU"]

CONE_LENGTH_LU = 0.15
"""Distance from the observer at which an exclusion cone's rim is drawn, LU (57,660 km)."""

LABEL_MIN_DISTANCE_LU = 0.1
"""An observer's name is drawn beside it only this far from the Earth's centre or farther, LU
(38,440 km, about 60 pixels in the system view): a ground station's name would sit on the Earth's
and hide it. Closer observers keep their name as the point's label, shown on hover."""

_CONE_COLORS = {"sun": (255, 210, 40), "earth": (80, 140, 255), "moon": (200, 200, 200)}


def observers_of(sensor) -> dict:
    """Key -> sensor of each observer: a network's members, else the one sensor as "observer"."""
    members = getattr(sensor, "members", None)
    return dict(members) if isinstance(members, dict) else {"observer": sensor}


def cone_rim(apex: np.ndarray, axis: np.ndarray, half_angle: float, length: float, n: int = 48) -> np.ndarray:
    """Points (n + 1, 3) of a cone's rim: apex (3,), unit axis (3,), half-angle rad, slant length."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    v = np.cross(axis, helper)
    v /= np.linalg.norm(v)
    w = np.cross(axis, v)
    phi = np.linspace(0.0, 2.0 * np.pi, n + 1)[:, None]
    dirs = np.cos(half_angle) * axis + np.sin(half_angle) * (np.cos(phi) * v + np.sin(phi) * w)
    return apex + length * dirs


def log_observers(rec, run, step, view, reach_to: np.ndarray) -> None:
    """Log every observer of ``run`` at ``step`` through ``view`` (the recorder's frame);
    ``reach_to`` (3,) synodic LU is where lines of sight should reach past (the estimate)."""
    t = float(step.t)
    earth = primary_positions(system_mu(run.dynamics))[0]
    by_key: dict[str, list] = {}
    for m in step.group or ((step.measurement,) if step.measurement is not None else ()):
        by_key.setdefault(getattr(m, "site", "") or "observer", []).append(m)
    for key, sensor in observers_of(run.sensor).items():
        base = f"world/observers/{key}"
        obs = np.asarray(sensor.observer_position(t), dtype=float).reshape(3)
        far = bool(np.linalg.norm(obs - earth) >= LABEL_MIN_DISTANCE_LU)
        rec.log(base, rr.Points3D(view.positions(obs, t) * LU_KM, colors=[(0, 230, 120)],
                                  labels=[key], show_labels=far, radii=rr.Radius.ui_points(5.0)))
        segs = []
        for m in by_key.get(key, ()):
            los = np.asarray(sensor.line_of_sight(np.asarray(m.z, dtype=float)[None, :2], t), dtype=float).reshape(3)
            end = obs + 1.2 * max(float(np.linalg.norm(reach_to - obs)), 1e-6) * los
            segs.append(view.positions(np.stack([obs, end]), t) * LU_KM)
        if segs:
            rec.log(f"{base}/line_of_sight", rr.LineStrips3D(segs, colors=[(0, 230, 120)], radii=rr.Radius.ui_points(1.0)))
        else:
            rec.log(f"{base}/line_of_sight", rr.Clear(recursive=False))
        cones = getattr(sensor, "exclusion_cones", None)
        for body, (axis, half) in (cones(t).items() if callable(cones) else ()):
            rim = cone_rim(obs, axis, half, CONE_LENGTH_LU)
            rec.log(f"{base}/exclusion/{body}", rr.LineStrips3D(
                [view.positions(rim, t) * LU_KM], colors=[_CONE_COLORS.get(body, (255, 255, 255))],
                radii=rr.Radius.ui_points(0.8), labels=[f"{body} exclusion"]))
