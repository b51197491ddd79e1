"""The PGM's ``pgm-reanchor`` step: ``arcs``, ``across-gaps`` and ``off``.

Each component is the re-anchoring's settings; :meth:`start` makes the state of one run
(:class:`.reanchoring.Reanchoring`, whose module docstring says what a re-anchoring does).
"""
from __future__ import annotations

from cistrack.interfaces.component import check_int, check_positive
from cistrack.interfaces.pgm_steps import Reanchor

from .reanchoring import REANCHOR_MODES, Reanchoring

__all__ = ["AcrossGapsReanchor", "ArcsReanchor", "NoReanchor", "REANCHOR_MODES"]


class ArcsReanchor(Reanchor):
    """At the end of every pass, from an arc's second pass on, batch least squares over the arc's
    measurements replaces the belief when a fit is accepted; fits never span a gap.

    Parameters
    ----------
    reanchor_gap_days : float
        A gap between updates at least this long ends an arc.
    reanchor_pause_hours : float
        A pause between updates at least this long ends a pass (the attempt is made at the
        prediction that crosses it).
    reanchor_measurements : int
        Measurements an arc needs before an attempt.
    reanchor_starts : int
        Most fits started, from the best-fitting posterior particles.
    """

    mode = "arcs"

    def __init__(self, reanchor_gap_days: float = 5.0, reanchor_pause_hours: float = 3.0,
                 reanchor_measurements: int = 6, reanchor_starts: int = 8):
        self.reanchor_gap_days = check_positive(self, "reanchor_gap_days", reanchor_gap_days)
        self.reanchor_pause_hours = check_positive(self, "reanchor_pause_hours", reanchor_pause_hours)
        self.reanchor_measurements = check_int(self, "reanchor_measurements", reanchor_measurements, minimum=1)
        self.reanchor_starts = check_int(self, "reanchor_starts", reanchor_starts, minimum=1)

    def start(self) -> Reanchoring:
        """A fresh re-anchoring state for one run."""
        return Reanchoring(self.mode, self.reanchor_gap_days, self.reanchor_pause_hours,
                           self.reanchor_measurements, self.reanchor_starts)


class AcrossGapsReanchor(ArcsReanchor):
    """Fits that also span gaps: after a gap, once its first pass is over, the belief becomes the
    fit's line of variations (Examples 2 and 3).

    Parameters
    ----------
    reanchor_gap_days : float
        A gap between updates at least this long ends an arc; the fits then span it.
    """

    mode = "across-gaps"


class NoReanchor(Reanchor):
    """No re-anchoring: the PGM alone (the paper's)."""

    def start(self) -> None:
        """None: this run never re-anchors."""
        return None
