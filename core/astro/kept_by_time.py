"""Results of an evaluation at single times, kept for the next request of the same time.

Shared by the observer states (:mod:`.observer`) and the real Earth-Moon frame (:mod:`.earth_moon`):
both are asked again and again for the same few times (the filter's stops), and each evaluation
runs ERFA or DE421.
"""
from __future__ import annotations

from collections.abc import Hashable
from typing import Callable, TypeVar

__all__ = ["kept_or_evaluated"]

T = TypeVar("T")
K = TypeVar("K", bound=Hashable)


def kept_or_evaluated(kept: dict[K, T], key: K, limit: int, evaluate: Callable[[], T]) -> T:
    """``kept[key]``, or ``evaluate()`` stored there first; at most ``limit`` entries, the oldest
    dropped first (``kept`` is a plain dict: insertion order)."""
    hit = kept.get(key)
    if hit is None:
        hit = evaluate()
        if len(kept) >= limit:
            try:
                kept.pop(next(iter(kept)), None)
            except (RuntimeError, StopIteration):  # another thread changed it meanwhile
                pass
        kept[key] = hit
    return hit
