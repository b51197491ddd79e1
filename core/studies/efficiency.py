"""How close a filter comes to the best precision the data allow: its RMS position error across
the runs of a study divided by the information bound's RMS (``bound_pos_km``, see
:mod:`cistrack.evaluation.information_bound`), at the end of every pass and at the end of the run.

1 is the bound itself (an efficient estimator); 2 means the filter's errors are twice what the
data allow. Every run that has both numbers counts, diverged ones included: the ratio is honest
about losses rather than flattering.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Efficiency", "group_efficiency", "efficiency_text"]


@dataclass(frozen=True)
class Efficiency:
    """A filter's efficiency over a group of runs.

    Attributes
    ----------
    final : float or None       RMS final position error / RMS final bound (None without a bound)
    final_runs : int            runs with both numbers at the end
    bound_km : float or None    RMS of the final bound, km
    by_pass : dict              pass number (int) -> ratio at the end of that pass, for passes that
                                every counted run observed
    """

    final: float | None = None
    final_runs: int = 0
    bound_km: float | None = None
    by_pass: dict[int, float] = field(default_factory=dict)


def _rms(values: list[float]) -> float:
    return math.sqrt(sum(v * v for v in values) / len(values))


def _ratio(pairs: list[tuple[Any, Any]]) -> tuple[float | None, int, float | None]:
    ok = [(float(e), float(b)) for e, b in pairs if e is not None and b is not None
          and math.isfinite(float(e)) and math.isfinite(float(b)) and float(b) > 0]
    if not ok:
        return None, 0, None
    bound = _rms([b for _, b in ok])
    return _rms([e for e, _ in ok]) / bound, len(ok), bound


def group_efficiency(summaries: list[Any]) -> Efficiency:
    """The :class:`Efficiency` of run summaries (:class:`cistrack.evaluation.run_summary.RunSummary`):
    the final ratio over the runs that ended normally (a filter that raised has no final state),
    the pass ends' over every run that reached them."""
    final, n, bound = _ratio([(s.final.get("pos_err_km"), s.final.get("bound_pos_km")) for s in summaries
                              if s.ended_normally])
    passes = sorted({int(p) for s in summaries for p in s.pass_end}, key=int)
    by_pass = {}
    for p in passes:
        ends = [s.pass_end.get(str(p)) or {} for s in summaries]
        if any("bound_pos_km" not in e for e in ends):
            continue
        ratio, _, _ = _ratio([(e.get("pos_err_km"), e.get("bound_pos_km")) for e in ends])
        if ratio is not None:
            by_pass[p] = ratio
    return Efficiency(final, n, bound, by_pass)


def efficiency_text(e: Efficiency) -> str:
    """'final 1.4 (bound 6.3 km, 20 runs); at pass ends 1: 3.2, 2: 2.1, ...', or '-' without a bound."""
    if e.final is None:
        return "-"
    passes = ", ".join(f"{p}: {r:.2g}" for p, r in e.by_pass.items())
    return (f"final {e.final:.3g} (RMS bound {e.bound_km:.3g} km, {e.final_runs} runs)"
            + (f"; at pass ends {passes}" if passes else ""))
