"""The study report's table for a terminal: the columns a person compares, within 120 characters.

summary.md and summary.csv keep every column (per-axis sigmas, wall-time spreads, calibration);
the terminal shows per scenario one line per filter x IOD: custody, median day lost, verdict
counts, the median final position error, the every-update ANEES, the largest final position
sigma (median) and the median wall time. Longer prose lines are wrapped to the same width.
"""
from __future__ import annotations

import textwrap
from typing import Any

__all__ = ["WIDTH", "terminal_table", "wrap_lines"]

WIDTH = 120
"""Characters per terminal line."""


def _g(v: Any, spec: str = ".3g") -> str:
    if v is None or (isinstance(v, float) and v != v):
        return "-"
    return format(v, spec) if isinstance(v, (int, float)) else str(v)


def terminal_table(rows: list[dict[str, Any]], has_truth: bool, counted: tuple[str, ...]) -> list[str]:
    """Lines of the compact table (see the module docstring); ``counted``: the verdict kinds of the
    ``verdicts`` column, in order."""
    header = ["filter", "iod", *(["custody", "lost d"] if has_truth else ["truth"]),
              "verdicts",
              *(["pos err km", "ANEES"] if has_truth else []), "max sigma km", "wall s"]
    out: list[str] = []
    by_scenario: dict[str, list[list[str]]] = {}
    for r in rows:
        sig = max((r[k] for k in ("sigma_x_km", "sigma_y_km", "sigma_z_km") if r.get(k) is not None), default=None)
        cells = [r["filter"], r["iod"]]
        if has_truth:
            cells += ["-" if r["custody_kept"] is None else f"{r['custody_kept']}/{r['runs']}", _g(r["median_lost_day"])]
        else:
            cells += ["none"]
        cells += [r["verdicts"]]
        if has_truth:
            cells += [_g(r["pos_err_km"]),
                      _g(r["anees_every_update"])]
        cells += [_g(sig), _g(r["wall_time_s"])]
        by_scenario.setdefault(r["scenario"], []).append(cells)
    every = [c for cells in by_scenario.values() for c in cells]
    widths = [max(len(h), *(len(c[i]) for c in every)) if every else len(h) for i, h in enumerate(header)]
    for scenario, lines in by_scenario.items():
        out.append(f"scenario {scenario}:")
        out.append("  " + "  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip())
        out += ["  " + "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip() for cells in lines]
    out.append("  verdicts: runs " + " / ".join(counted))
    return [line if len(line) <= WIDTH else line[:WIDTH - 1] + "~" for line in out]


def wrap_lines(lines: list[str], width: int = WIDTH) -> list[str]:
    """Prose lines wrapped at ``width`` (continuations indented by four spaces); table lines and
    short lines unchanged."""
    out: list[str] = []
    for line in lines:
        if len(line) <= width:
            out.append(line)
            continue
        lead = len(line) - len(line.lstrip(" "))
        out += textwrap.wrap(line, width, initial_indent=" " * lead, subsequent_indent=" " * (lead + 4),
                             break_on_hyphens=False, break_long_words=False) or [line]
    return out
