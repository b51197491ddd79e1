"""Schedule: when the sensor is tasked to observe."""
from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from cistrack.errors import ConfigError
from cistrack.interfaces.component import Component

__all__ = ["Pass", "Schedule", "checked_plan", "PLAN_TOLERANCE_TU"]


@dataclass(frozen=True)
class Pass:
    """An interval during which the target is visible: start and end, TU since the epoch."""

    start: float
    end: float

    @property
    def duration(self) -> float:
        return self.end - self.start


class Schedule(Component):
    """A tasking policy: chooses measurement times inside the target's visibility passes."""

    kind = "schedule"

    @abstractmethod
    def plan(self, passes: Sequence[Pass], t_end: float, rng: np.random.Generator) -> np.ndarray:
        """Measurement times (J,) TU, strictly increasing, each inside one of ``passes``,
        none after ``t_end``. Random choices use ``rng`` only."""


PLAN_TOLERANCE_TU = 1e-9
"""How far (TU, about 0.4 ms) a planned time may lie outside its pass or after the run's end."""


def checked_plan(planned: Any, passes: list, t_end: float, who: str) -> np.ndarray:
    """The planned times as a (J,) float array, refused (ConfigError naming ``who``) unless they are
    what the Schedule interface promises: finite, strictly increasing, each inside a pass, none
    before 0 or after ``t_end``."""
    try:
        t = np.asarray(planned, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{who} returned {type(planned).__name__} {str(planned)[:60]!r}, not times "
                          "(a (J,) array of TU)") from None
    if t.ndim != 1:
        raise ConfigError(f"{who} returned an array of shape {t.shape}; a schedule returns a (J,) array of times (TU)")
    bad = []
    if not np.all(np.isfinite(t)):
        bad.append("NaN or infinite times")
    elif t.size and (t[0] < -PLAN_TOLERANCE_TU or t[-1] > t_end + PLAN_TOLERANCE_TU):
        bad.append(f"times outside the run (0 to {t_end:.6g} TU)")
    if not np.all(np.diff(t) > 0):
        bad.append("times that do not increase strictly")
    if not bad:
        inside = np.zeros(t.shape, dtype=bool)
        for p in passes:
            inside |= (t >= p.start - PLAN_TOLERANCE_TU) & (t <= p.end + PLAN_TOLERANCE_TU)
        if not inside.all():
            bad.append(f"{int((~inside).sum())} times outside every visibility pass (the first at "
                       f"{t[~inside][0]:.6g} TU)")
    if bad:
        raise ConfigError(f"{who} returned " + " and ".join(bad) + "; a schedule's times lie inside the "
                          "target's visibility passes (cistrack plugins --check NAME tests a schedule)")
    return t
