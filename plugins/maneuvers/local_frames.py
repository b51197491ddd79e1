"""Local frames of a burn: radial/in-track/cross-track about the Moon or the Earth, and
velocity-normal-binormal, all resolved in the synodic frame.

Each frame is three unit vectors (the columns of :func:`frame_axes`), in the order a burn's
``vector_ms`` gives its components:

``rtn-moon``   R, T, N with r the position relative to the Moon and v the synodic velocity:
               R = r/|r| (radial), N = r x v / |r x v| (cross-track, the orbit normal),
               T = N x R (in-track: along the motion, perpendicular to R)
``rtn-earth``  the same relative to the Earth
``vnb``        V = v/|v| (in-track: exactly along the synodic velocity), N = r x v / |r x v| with
               r relative to the Moon (cross-track), B = V x N (radial: in the orbit plane,
               perpendicular to the velocity)
``synodic``    x, y, z of the synodic frame (a burn there is given as a vector)

A direction names one axis and its sign: ``radial``, ``in-track`` and ``cross-track`` (R, T, N
or B, V, N), ``anti-...`` the opposite. The Moon and the Earth are where the dynamics model puts
its primaries of those names (``Body.position_at``); a model without them (a third party's) gets
the Earth-Moon CR3BP's positions.
"""
from __future__ import annotations

import numpy as np

from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.errors import ConfigError

__all__ = ["FRAMES", "DIRECTIONS", "frame_axes", "direction_vector", "body_position"]

FRAMES: tuple[str, ...] = ("rtn-moon", "rtn-earth", "vnb", "synodic")
"""The local frames a burn can be given in."""

DIRECTIONS: tuple[str, ...] = ("in-track", "anti-in-track", "radial", "anti-radial", "cross-track",
                               "anti-cross-track")
"""The directions a burn can be given as (an axis of its frame and a sign)."""

_AXIS = {  # frame -> direction -> column of frame_axes
    "rtn-moon": {"radial": 0, "in-track": 1, "cross-track": 2},
    "rtn-earth": {"radial": 0, "in-track": 1, "cross-track": 2},
    "vnb": {"in-track": 0, "cross-track": 1, "radial": 2},
}
_CR3BP = {"moon": np.array([1.0 - MU_EARTH_MOON, 0.0, 0.0]), "earth": np.array([-MU_EARTH_MOON, 0.0, 0.0])}


def body_position(dynamics, name: str, t: float) -> np.ndarray:
    """Synodic position (3,) LU of the primary ``name`` ("Moon", "Earth") of ``dynamics`` at ``t``
    (TU); the Earth-Moon CR3BP's when the model has no primary of that name."""
    find = getattr(dynamics, "primary", None)
    body = find(name) if callable(find) else None
    if body is None:
        return _CR3BP[name.lower()].copy()
    return np.asarray(body.position_at(t), dtype=float).reshape(3)


def _unit(v: np.ndarray, what: str, frame: str) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if not np.isfinite(n) or n <= 1e-14:
        raise ConfigError(f"burn frame {frame!r}: the {what} is zero at the burn; the frame is undefined there "
                          "(give the burn in another frame or as a synodic vector)")
    return v / n


def frame_axes(frame: str, state: np.ndarray, t: float, dynamics) -> np.ndarray:
    """The frame's unit vectors (3, 3) as columns, synodic, for the synodic ``state`` (6,) at
    ``t`` (TU) under ``dynamics``. Raises ConfigError for an unknown frame or one undefined at
    the state (zero velocity, or position parallel to the velocity)."""
    if frame == "synodic":
        return np.eye(3)
    if frame not in FRAMES:
        raise ConfigError(f"unknown burn frame {frame!r}; one of {', '.join(FRAMES)}")
    x = np.asarray(state, dtype=float).reshape(6)
    center = body_position(dynamics, "Earth" if frame == "rtn-earth" else "Moon", t)
    r, v = x[:3] - center, x[3:]
    n = _unit(np.cross(r, v), "angular momentum (position x velocity)", frame)
    if frame == "vnb":
        vv = _unit(v, "velocity", frame)
        return np.column_stack([vv, n, np.cross(vv, n)])
    rr = _unit(r, "position", frame)
    return np.column_stack([rr, np.cross(n, rr), n])


def direction_vector(frame: str, direction: str, magnitude: float) -> np.ndarray:
    """The components (3,) in ``frame`` of a burn of ``magnitude`` along ``direction``."""
    if frame not in _AXIS:
        raise ConfigError(f"a burn in frame {frame!r} is given as a vector (vector_ms), not a direction")
    base = direction.removeprefix("anti-")
    if base not in _AXIS[frame]:
        raise ConfigError(f"unknown burn direction {direction!r}; one of {', '.join(DIRECTIONS)}")
    out = np.zeros(3)
    out[_AXIS[frame][base]] = -magnitude if direction.startswith("anti-") else magnitude
    return out
