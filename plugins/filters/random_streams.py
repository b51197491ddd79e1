"""Random streams of their own for work that must not move a filter's main stream."""
from __future__ import annotations

import numpy as np

__all__ = ["independent_stream"]


def independent_stream(rng: np.random.Generator) -> np.random.Generator:
    """A generator independent of ``rng`` whose creation leaves ``rng``'s own draws unchanged: a
    child of its seed sequence. A generator without one (built from a raw state) gives up one
    draw to seed the child instead."""
    try:
        return rng.spawn(1)[0]
    except TypeError:
        return np.random.default_rng(int(rng.integers(2**63)))
