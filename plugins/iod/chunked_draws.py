"""The Monte Carlo draws of the kinematic IOD in chunks, with the numbers of one whole draw.

The IOD draws a batch of n samples as ``angles = draw_angles(n)`` (n, K, 2) and then
``rho = draw_ranges(n)`` (n, K). Fitting all n at once needs about 1 KB per sample (angles, ranges,
the (K, 6, n) fit data and their temporaries), so with 5x oversampling the memory grew with the
oversampling factor: 6,000,000 particles failed on a 30,000,000-sample batch.

:func:`draw_in_chunks` hands out the same numbers a chunk at a time. A numpy Generator's
elementwise draws (``standard_normal``, ``uniform``, ...) do not depend on how a request is split:
drawing a + b values gives the a values and then the b values. The angles of the whole batch come
before its ranges in the stream, so the ranges of chunk 1 lie after the angles of the last chunk.
The generator is therefore walked twice: a copy skips over every angle draw to the state where the
ranges start, then one copy replays the angles chunk by chunk while the caller's generator draws
the ranges chunk by chunk. The caller's generator ends where one whole draw would have left it,
so everything drawn after the IOD (the filter's draws) is unchanged too. The price is drawing the
angles twice when a batch spans more than one chunk (a few percent of the IOD's time).

This holds for range priors whose ``draw`` makes elementwise draws in C order of the requested
shape, as both built-in priors do (``tests/iod/test_iod_chunks.py`` checks them).
"""
from __future__ import annotations

from typing import Callable, Iterator

import numpy as np

__all__ = ["CHUNK_SAMPLES", "draw_in_chunks"]

CHUNK_SAMPLES = 131_072
"""Samples fitted at once: about 150 MB of work arrays with 12 fitted measurements."""

Draw = Callable[[int, "np.random.Generator"], np.ndarray]  # a string: numpy.random loads on use


def _copy(rng: np.random.Generator, state: dict) -> np.random.Generator:
    bit_generator = type(rng.bit_generator)()
    bit_generator.state = state
    return np.random.Generator(bit_generator)


def draw_in_chunks(n: int, rng: np.random.Generator, draw_angles: Draw, draw_ranges: Draw,
                   chunk: int = CHUNK_SAMPLES) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """(angles (c, K, 2), ranges (c, ...)) for consecutive chunks of ``n`` samples (c <= ``chunk``).

    Concatenated, the chunks equal ``draw_angles(n, rng)`` followed by ``draw_ranges(n, rng)``,
    and ``rng`` is left in the same state.
    """
    if chunk < 1:
        raise ValueError(f"chunk must be >= 1, got {chunk}")
    if n <= chunk:
        angles = draw_angles(n, rng)
        yield angles, draw_ranges(n, rng)
        return
    start = rng.bit_generator.state
    skip = _copy(rng, start)
    for lo in range(0, n, chunk):
        draw_angles(min(chunk, n - lo), skip)
    replay = _copy(rng, start)
    rng.bit_generator.state = skip.bit_generator.state  # the ranges start after every angle
    for lo in range(0, n, chunk):
        c = min(chunk, n - lo)
        angles = draw_angles(c, replay)
        yield angles, draw_ranges(c, rng)
