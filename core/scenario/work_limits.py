"""Up-front limits on the work a scenario asks for, and on the times it may name.

Like the memory checks of :mod:`cistrack.scenario.limits`, these refuse a value before anything
is built from it, with a :class:`~cistrack.errors.ConfigError` naming where the value came from
(``where``: a file and key, or a flag), the estimate of the work, and what is allowed:

- :func:`check_steps`: the filter steps a run would take (measurement times and prediction-only
  steps); each is a filter prediction, often an update, and one row of the results table, so the
  count scales both the time and the memory of a run.
- :func:`check_epoch_span`: the scenario's epoch and the end of its span (epoch + duration) lie in
  the years whose time scales and calendar arithmetic cistrack supports.
"""
from __future__ import annotations

import math
from datetime import datetime, timedelta, timezone

from cistrack.errors import ConfigError
from cistrack.interfaces.limits import MAX_STEPS  # defined where schedules reach it

__all__ = ["MAX_STEPS", "EPOCH_MIN", "EPOCH_MAX", "check_steps", "check_epoch_span", "span_text"]

EPOCH_MIN = datetime(1800, 1, 1, tzinfo=timezone.utc)
EPOCH_MAX = datetime(2200, 1, 1, tzinfo=timezone.utc)
"""A scenario's span (epoch to epoch + duration) must lie within [EPOCH_MIN, EPOCH_MAX]: the
years for which its time scales (UTC, TT, TDB, UT1) are meant to be used and calendar dates
never overflow. Components may allow less (DE421, the ephemeris of the ``real-telescope``
sensor and the ``ephemeris`` dynamics, covers 1900 to 2052)."""


def span_text() -> str:
    """The allowed span of epochs, for messages."""
    return f"{EPOCH_MIN:%Y-%m-%d} to {EPOCH_MAX:%Y-%m-%d}"


def check_steps(n_steps: float, where: str, what: str) -> None:
    """Refuse a run whose estimated number of filter steps ``n_steps`` exceeds :data:`MAX_STEPS`.

    ``where`` names the key or file, ``what`` says what makes the steps (e.g. "a prediction
    every 1e-07 h over 1.4 days")."""
    if math.isnan(n_steps) or n_steps <= MAX_STEPS:
        return
    raise ConfigError(f"{where}: {what} makes about {n_steps:.3g} filter steps; at most {MAX_STEPS:,} "
                      "are allowed (each step is a filter prediction or update and a results row); "
                      "take fewer (a longer interval, a shorter duration_days, or fewer observations)")


def check_epoch_span(epoch: datetime, duration_days: float, where: str) -> None:
    """Refuse an ``epoch`` (or an epoch + ``duration_days``) outside [EPOCH_MIN, EPOCH_MAX].

    ``where`` names the epoch key (e.g. "s.toml: top level: key 'epoch'")."""
    e = epoch.astimezone(timezone.utc)
    shown = f"{e.year:04d}-{e.month:02d}-{e.day:02d}T{e.hour:02d}:{e.minute:02d}:{e.second:02d}Z"
    if not EPOCH_MIN <= epoch <= EPOCH_MAX:
        raise ConfigError(f"{where} = {shown!r} is outside the years cistrack supports: the epoch "
                          f"must lie from {span_text()} (UTC)")
    try:
        end = epoch + timedelta(days=duration_days)
    except OverflowError:
        end = EPOCH_MAX + timedelta(days=1)
    if end > EPOCH_MAX:
        raise ConfigError(f"{where} = {shown!r} with duration_days = {duration_days:g} ends after "
                          f"{EPOCH_MAX:%Y-%m-%d}: the scenario's span must lie from {span_text()} (UTC)")
