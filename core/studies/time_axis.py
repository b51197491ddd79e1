"""A time axis that shrinks long gaps without measurements, so the passes around them stay legible.

Example 3 has a 150-day sensor shutoff in a 160-day run: on a plain axis the decisive pass after
the gap is a sliver at the right edge. :class:`GapAxis` maps time (days) piecewise linearly onto
an axis on which every gap longer than ``min_gap_days`` (and than ``min_fraction`` of the span)
takes ``gap_width`` of the axis; :meth:`GapAxis.inverse` maps back for tick labels, and the
figure marks each shrunk gap with its length.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GapAxis"]


@dataclass(frozen=True)
class GapAxis:
    """Piecewise-linear time axis. ``gaps`` (G, 2): start and end (days) of each shrunk gap;
    ``width``: the axis length (days of the shrunk axis) each gap takes."""

    gaps: np.ndarray
    width: float

    @classmethod
    def from_times(cls, days: np.ndarray, t0: float, t1: float, *, min_gap_days: float = 10.0,
                   min_fraction: float = 0.2, gap_width: float = 0.04) -> "GapAxis":
        """Gaps between consecutive ``days`` (measurement times, (K,)) within [t0, t1] longer than
        ``min_gap_days`` and ``min_fraction`` of the span; each then takes ``gap_width`` of what
        the axis keeps."""
        d = np.sort(np.asarray(days, dtype=float))
        d = d[np.isfinite(d)]
        span = float(t1 - t0)
        if d.size < 2 or span <= 0:
            return cls(np.zeros((0, 2)), 0.0)
        starts, ends = d[:-1], d[1:]
        long = (ends - starts) > max(min_gap_days, min_fraction * span)
        gaps = np.column_stack([starts[long], ends[long]])
        kept = span - float(np.sum(gaps[:, 1] - gaps[:, 0])) if gaps.size else span
        return cls(gaps, gap_width * kept if gaps.size else 0.0)

    @property
    def shrinks(self) -> bool:
        return self.gaps.shape[0] > 0

    def forward(self, t: np.ndarray) -> np.ndarray:
        """Days -> axis position (same shape)."""
        t = np.asarray(t, dtype=float)
        x = t.copy()
        for a, b in self.gaps:
            length = b - a
            inside = (t > a) & (t < b)
            x = np.where(t >= b, x - (length - self.width), x)
            x = np.where(inside, x - (t - a) + (t - a) * self.width / length, x)
        return x

    def inverse(self, x: np.ndarray) -> np.ndarray:
        """Axis position -> days (the inverse of :meth:`forward`)."""
        x = np.asarray(x, dtype=float)
        t = x.copy()
        shift = 0.0
        for a, b in self.gaps:  # in time order: each gap's start on the axis is a - shift so far
            length = b - a
            xa = a - shift
            inside = (x > xa) & (x < xa + self.width)
            t = np.where(inside, a + (x - xa) * length / self.width, t)
            t = np.where(x >= xa + self.width, t + (length - self.width), t)
            shift += length - self.width
        return t
