"""The fit of the latest arc of a multi-arc file, and the residual ladder of the others.

:func:`latest_arc_fit` takes the fit of the latest long-gap arc (rule 1 of
:mod:`cistrack.fitting.arcs`; the fit ``cistrack fit`` makes from the filter run over that arc)
and applies rule 2 inside it: when the arc holds groups more than ``link_gap_days`` apart, the
latest group is fitted again on its own (from the arc's fit) and the earlier groups are joined
one at a time while the fit of what is joined predicts them. When every group joins, the arc's
own fit is kept unchanged; otherwise the joined groups' fit replaces it. Every arc left out (the
earlier long-gap arcs and the groups behind a broken link) gets a rung of the residual ladder
(:mod:`cistrack.fitting.residual_ladder`) against the fit that is kept.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cistrack.errors import CistrackError
from cistrack.fitting.arcs import LINK_GAP_DAYS, LONG_GAP_DAYS, ArcSpan, link_latest_arc, long_gap_arcs, observation_groups
from cistrack.fitting.residual_ladder import Rung, residual_ladder
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.result import FitResult
from cistrack.model.measurement import MeasurementSet

__all__ = ["ArcFit", "latest_arc_fit", "ladder_verdicts"]


@dataclass
class ArcFit:
    """The fit to report and predict from, and what it leaves out.

    fit : FitResult          over ``rows`` of the full set
    rows : (n,) int          rows of the full measurement set that the fit used
    earlier : list[ArcSpan]  the arcs left out (rows of the full set), oldest first
    ladder : list[Rung]      one rung per ``earlier`` arc, same order
    notes : list[str]        what was decided, in words
    """

    fit: FitResult
    rows: np.ndarray
    earlier: list = field(default_factory=list)
    ladder: list = field(default_factory=list)
    notes: list = field(default_factory=list)


def _offset(spans: list[ArcSpan], first_row: int) -> list[ArcSpan]:
    return [ArcSpan(s.rows + first_row, s.start, s.end, s.gap_before_days) for s in spans]


def _linked(dynamics, sensor, arc_ms: MeasurementSet, fit: FitResult, options: FitOptions,
            link_gap_days: float):
    """Rule 2 inside the latest long-gap arc: (fit, rows of ``arc_ms``, left-out spans, note)."""
    groups = observation_groups(arc_ms.times, link_gap_days)
    if len(groups) == 1:
        return fit, np.arange(len(arc_ms)), [], ""

    def refit(sub: MeasurementSet, start: FitResult) -> FitResult:
        return fit_orbit(dynamics, sensor, sub, start.state, start.epoch, options=options)

    try:
        first = refit(arc_ms.subset(groups[-1].rows), fit)
    except CistrackError as exc:
        return fit, np.arange(len(arc_ms)), [], f"the latest group alone could not be fitted ({exc}); links not tested"
    linked = link_latest_arc(dynamics, sensor, arc_ms, first, refit, link_gap_days)
    if not linked.earlier:
        return fit, np.arange(len(arc_ms)), [], ""
    why = linked.rungs[-1].why
    return (linked.fit, linked.arc.rows, linked.earlier,
            f"{sum(s.n for s in linked.earlier)} earlier observations left out: no single orbit explains them and "
            f"the later ones ({why})")


def latest_arc_fit(dynamics, sensor, everything: MeasurementSet, fit: FitResult, options: FitOptions | None = None,
                   long_gap_days: float = LONG_GAP_DAYS, link_gap_days: float = LINK_GAP_DAYS) -> ArcFit:
    """The latest arc's fit and the ladder of the others (module docstring).

    ``everything``: all observations of the object (K rows, TU in the time base of ``dynamics``
    and ``sensor``; ``sensor`` must know every site of it); ``fit``: the fit of its latest
    long-gap arc (the rows after its last gap of more than ``long_gap_days``), e.g. the fit of
    the filter run over that arc; ``options``: the least squares' options for the refits.
    """
    opts = options or FitOptions()
    arcs = long_gap_arcs(everything.times, long_gap_days)
    latest = arcs[-1]
    arc_ms = everything.subset(latest.rows)
    kept, rows, left, note = _linked(dynamics, sensor, arc_ms, fit, opts, link_gap_days)
    earlier = arcs[:-1] + _offset(left, int(latest.rows[0]))
    out = ArcFit(kept, rows + int(latest.rows[0]), earlier, [], [note] if note else [])
    out.ladder = residual_ladder(kept, dynamics, sensor, everything, earlier) if earlier else []
    if len(arcs) > 1:
        out.notes.insert(0, f"{len(arcs)} arcs more than {long_gap_days:g} days apart: the latest is fitted, "
                            "the others are predicted (residual ladder)")
    return out


def ladder_verdicts(ladder: list[Rung]) -> str:
    """One line for the summary: how many earlier arcs are consistent, broken or lost."""
    counts = {v: sum(r.verdict == v for r in ladder) for v in ("consistent", "broken", "prediction lost")}
    return ", ".join(f"{n} {v}" for v, n in counts.items() if n)
