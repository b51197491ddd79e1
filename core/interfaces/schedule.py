"""Schedule: when the sensor is tasked to observe."""
from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from cistrack.interfaces.component import Component

__all__ = ["Pass", "Schedule"]


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
