"""What the blueprint is set from: the run's span on the ``utc`` timeline and the points the
system view frames; and where a step sits on the recording's timelines."""
from __future__ import annotations

from datetime import datetime

import numpy as np

from cistrack.units import LU_KM, TU_S, leap_seconds, tu_to_utc

from .scene import libration_points, primary_positions, system_mu
from .view_frame import ViewFrame

__all__ = ["utc_range_s", "system_points_km", "utc_at", "set_step_times"]


def utc_at(epoch: datetime, t_tu: float) -> datetime:
    """The UTC instant ``t_tu`` (TU elapsed) after the scenario ``epoch``: its label, as the
    files give it (:func:`cistrack.units.tu_to_utc`)."""
    return tu_to_utc(epoch, t_tu)


def set_step_times(rec, event: int, index: int, when: datetime) -> None:
    """Set the recording's ``event``, ``step`` and ``utc`` timelines for what is logged next."""
    rec.set_time("event", sequence=int(event))
    rec.set_time("step", sequence=int(index))
    rec.set_time("utc", timestamp=when)


def utc_range_s(run, epoch) -> tuple[float, float] | None:
    """First and last time of the run's steps on ``utc``, unix seconds: from the IOD epoch to the
    last truth time or measurement (None when unknown). ``epoch``: the scenario epoch (datetime)."""
    ends = []
    truth = getattr(run, "truth_times", None)
    if truth is not None and len(truth):
        ends.append(float(np.max(truth)))
    times = getattr(getattr(run, "measurements", None), "times", None)
    if times is not None and len(times):
        ends.append(float(np.max(times)))
    start = float(getattr(getattr(run, "iod_cloud", None), "epoch", 0.0) or 0.0)
    if not ends or not max(ends) > start:
        return None
    t0 = epoch.timestamp()
    return _unix_s(epoch, t0, start), _unix_s(epoch, t0, max(ends))


def _unix_s(epoch: datetime, t0: float, t_tu: float) -> float:
    """Unix seconds (``t0`` at ``epoch``) of the label :func:`utc_at` gives ``t_tu``: the unix
    clock, like UTC labels, skips the leap seconds elapsed time counts."""
    leap = leap_seconds(epoch, utc_at(epoch, t_tu))
    return t0 + t_tu * TU_S if leap == 0.0 else t0 + t_tu * TU_S - leap


def system_points_km(run, view: ViewFrame | None = None) -> np.ndarray | None:
    """Points (N, 3) km the system view is framed on: Earth, Moon, L1 and L2 (synodic frame) and
    the truth trajectory (in ``view``'s frame)."""
    parts = []
    if view is None or view.is_synodic:
        mu = system_mu(run.dynamics)
        parts.append(primary_positions(mu))
        parts.append(libration_points(mu)[:2])
    truth = getattr(run, "truth_states", None)
    if truth is not None and len(truth):
        parts.append((view.states(truth, run.truth_times) if view is not None and not view.is_synodic
                      else np.asarray(truth, dtype=float))[:, :3])
    return np.concatenate(parts, axis=0) * LU_KM if parts else None
