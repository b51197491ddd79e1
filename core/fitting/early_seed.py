"""The filter over the first hours only, as the least squares' start.

``cistrack fit`` needs the filter for one thing: an orbit close enough to the least-squares
minimum for Levenberg-Marquardt to converge from it. After the kinematic IOD of the first pass
the range is known only within the admissible region; half a day of observations
(:data:`EARLY_DAYS`), with the parallax of the Earth's rotation and of several sites, narrows it
enough, and the least squares over the whole arc converges from the filter's estimate there to
the same minimum as from its estimate at the last observation. The filter's steps are most of a
fit's cost (measured in-process: 3.0 of the 8.7 CPU seconds of the shipped 65-observation
example; 0.7 over its first 25), so it runs over the first observations only (:func:`early_rows`).

The shortcut is kept only when that fit converged and looks clean (no contiguous block of
rejections, RMS within bounds: :func:`cistrack.least_squares.burn_search.suspicion`); otherwise
the filter runs over every observation, as without it, and the least squares starts from there.
"""
from __future__ import annotations

import numpy as np

from cistrack import units

__all__ = ["EARLY_DAYS", "MIN_LATER_SHARE", "SESSION_GAP_HOURS", "EARLY_COMPONENTS", "EARLY_PARTICLES",
           "early_rows", "early_starts", "early_particles"]

EARLY_DAYS = 0.5
"""The filter takes the observations up to this long after the first one (days), and at least the
first observing session. Measured: from half a day the least squares converges to the full run's
orbit on the shipped example (2 sites, 25 of 65 observations) and on a 3-site, 10-night arc (79 of
319), within 8e-5 sigma (``benchmarks/bench_fit.py``)."""
MIN_LATER_SHARE = 0.25
"""The shortcut is taken only when it leaves at least this share of the observations to the least
squares alone (otherwise the full filter run costs little more)."""
SESSION_GAP_HOURS = 3.0
"""Observations less than this apart belong to one observing session (hours)."""
EARLY_COMPONENTS = 3
"""After the filter's mean, the least squares starts from at most this many of its mixture's
components, heaviest first: half a day into the arc the filter's belief can still have several
modes, and their mean can lie between them (measured: with 1,000 particles on the shipped example
it could not be propagated over the arc)."""
EARLY_PARTICLES = 1000
"""At most this many particles in the IOD and the filter over the first hours (the scenario's own
count when smaller; the run over every observation, when the shortcut is not kept, has the
scenario's). The least squares only needs a start in the right basin: measured with 1,000 instead of
4,000, the fitted orbit moves by 3e-5 sigma on the shipped example and 2e-5 sigma on a 3-site,
10-night arc (``benchmarks/bench_fit.py``), and the filter's part of the fit costs 0.6 s less."""


def early_rows(times: np.ndarray, days: float = EARLY_DAYS) -> int:
    """How many leading observations the filter takes (``times``: (n,) TU, ascending): those up to
    ``days`` after the first, and at least the first observing session (the IOD's pass; a session
    ends at a gap of :data:`SESSION_GAP_HOURS`). 0 when that leaves fewer than
    :data:`MIN_LATER_SHARE` of the observations to the least squares alone."""
    t = np.asarray(times, dtype=float)
    if t.size < 2:
        return 0
    breaks = np.nonzero(np.diff(t) > float(units.hours_to_tu(SESSION_GAP_HOURS)))[0] + 1
    first_session = int(breaks[0]) if breaks.size else t.size
    k = max(first_session, int(np.searchsorted(t, t[0] + float(units.days_to_tu(days)), side="right")))
    return k if t.size - k >= MIN_LATER_SHARE * t.size else 0


def early_starts(belief) -> list:
    """Where the least squares may start from the filter's ``belief`` (a Belief whose ``mixture``
    has ``mean`` (6,), ``covariance`` (6, 6), ``weights`` (M,), ``means`` (M, 6) and ``covariances``
    (M, 6, 6), at ``belief.epoch`` TU): its mean, then up to :data:`EARLY_COMPONENTS` components,
    heaviest first (none when there is one); each a :class:`cistrack.fitting.restart.Restart`."""
    from cistrack.fitting.restart import Restart

    mix, t = belief.mixture, float(belief.epoch)
    starts = [Restart(0, "", t, np.asarray(mix.mean, dtype=float), np.asarray(mix.covariance, dtype=float),
                      "the filter's mean")]
    if len(mix.weights) > 1:
        for i in np.argsort(-np.asarray(mix.weights))[:EARLY_COMPONENTS]:
            starts.append(Restart(0, "", t, np.asarray(mix.means[i], dtype=float),
                                  np.asarray(mix.covariances[i], dtype=float), f"the filter's component {int(i)}"))
    return starts


def early_particles(raw: dict) -> dict:
    """The scenario table ``raw`` with ``n_particles`` of its ``[iod]`` and ``[filter]`` tables at
    most :data:`EARLY_PARTICLES` (a value that is not an integer is left for the scenario's own
    check to name)."""
    out = dict(raw)
    for table in ("iod", "filter"):
        part = out.get(table)
        n = part.get("n_particles") if isinstance(part, dict) else None
        if isinstance(n, int) and not isinstance(n, bool) and n > EARLY_PARTICLES:
            out[table] = {**part, "n_particles": EARLY_PARTICLES}
    return out
