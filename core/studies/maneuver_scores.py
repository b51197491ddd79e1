"""How well a study's runs caught the truth's burns: per run from its manifest summary and its
update rows, per report group aggregated.

Per truth burn of a run (``summary.truth_maneuvers``; a burn after the run's last update is never
observed and not scored):

- detected: an episode of ``summary.maneuvers`` (:mod:`cistrack.runs.maneuver_watch`) whose first
  detection (``t_days``) is after the burn and before the next truth burn, or the run's end; the
  first such episode scores the burn, later ones in the same window are repeats, not false alarms;
- the delay (days from the burn to that first detection) and in which pass it came: the
  ``pass_index`` of the detection's update row minus that of the first update after the burn
  (0 = within the next pass observed after the burn, 1 = the pass after that, ...);
- the delta-v error over its sigma, ``|dv_est - dv_true| / sigma``, when the episode is confirmed.

Per run: the false alarms (episodes matched to no truth burn: before the first burn, or any in a
run whose truth does not burn) and whether custody was kept.

Per group (:func:`group_maneuver_scores`): the number of burns, P(detect) with its 95 % Wilson
interval, P(detect within the next pass) and within two passes (with intervals), the median delay,
the share of confirmed estimates within 3 sigma, the runs with a false alarm over the runs (with
an interval) and custody kept over the runs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack.studies.calibration import wilson_interval

__all__ = ["BurnScore", "RunManeuverScore", "score_run", "update_rows", "group_maneuver_scores",
           "MANEUVER_COLUMNS", "has_maneuvers"]

_SAME_T = 1e-6
"""Days within which an episode's first detection is the time of an update row."""
WITHIN_SIGMA = 3.0
"""A confirmed delta-v estimate within this many sigmas of the truth's counts as consistent."""


@dataclass(frozen=True)
class BurnScore:
    """One truth burn of one run, as the run saw it (module docstring)."""

    t_days: float
    delta_v_ms: float
    detected: bool
    delay_days: float | None = None
    pass_offset: int | None = None
    """Passes after the first pass observed after the burn (0: within the next pass); None when
    not detected or the update rows have no pass index."""
    confirmed: bool = False
    dv_error_sigma: float | None = None


@dataclass(frozen=True)
class RunManeuverScore:
    """One run's burns (:class:`BurnScore`), its false alarms, repeat episodes and custody."""

    burns: list[BurnScore] = field(default_factory=list)
    false_alarms: int = 0
    repeats: int = 0
    custody_kept: bool | None = None


def _finite(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def update_rows(table: Any) -> list[dict]:
    """The update rows (t_days, pass_index) of a run's steps table (a pyarrow table or a list of
    row dicts), in time order."""
    rows = table.to_pylist() if hasattr(table, "to_pylist") else list(table)
    out = [{"t_days": _finite(r.get("t_days")), "pass_index": _finite(r.get("pass_index"))}
           for r in rows if r.get("kind", "update") == "update"]
    return sorted((r for r in out if r["t_days"] is not None), key=lambda r: r["t_days"])


def _pass_at(updates: list[dict], t: float, after: bool) -> float | None:
    """The pass index of the first update after ``t`` (``after``) or of the update at ``t``."""
    for r in updates:
        if (r["t_days"] > t) if after else abs(r["t_days"] - t) <= _SAME_T:
            return r["pass_index"]
    return None


def _dv_error(episode: dict, dv_true: float) -> float | None:
    est, sigma = _finite(episode.get("delta_v_ms")), _finite(episode.get("delta_v_sigma_ms"))
    if not episode.get("confirmed") or est is None or sigma is None or sigma <= 0:
        return None
    return abs(est - dv_true) / sigma


def _score_burn(burn: dict, window_end: float, episodes: list[dict], updates: list[dict]) -> tuple[BurnScore, int]:
    """The burn's score and the number of episodes in its window (after the first: repeats)."""
    t, dv = float(burn["t_days"]), float(burn.get("delta_v_ms") or 0.0)
    inside = [e for e in episodes if t < e["t"] <= window_end]
    if not inside:
        return BurnScore(t, dv, False), 0
    first = inside[0]
    p0, p1 = _pass_at(updates, t, after=True), _pass_at(updates, first["t"], after=False)
    offset = int(round(p1 - p0)) if p0 is not None and p1 is not None else None
    return BurnScore(t, dv, True, first["t"] - t, offset, bool(first["e"].get("confirmed")),
                     _dv_error(first["e"], dv)), len(inside)


def score_run(summary: dict, updates: list[dict]) -> RunManeuverScore:
    """The maneuver score of one run: ``summary`` its manifest summary (``maneuvers``,
    ``truth_maneuvers``, ``custody_kept``), ``updates`` its update rows (:func:`update_rows`)."""
    episodes = sorted(({"t": t, "e": e} for e in summary.get("maneuvers") or []
                       for t in [_finite(e.get("t_days"))] if t is not None), key=lambda x: x["t"])
    end = updates[-1]["t_days"] if updates else max([x["t"] for x in episodes], default=0.0)
    burns = sorted((b for b in summary.get("truth_maneuvers") or [] if _finite(b.get("t_days")) is not None
                    and (_finite(b.get("delta_v_ms")) or 0.0) > 0.0),  # a 0 m/s "burn" is none: not flown
                   key=lambda b: float(b["t_days"]))
    burns = [b for b in burns if float(b["t_days"]) < end]  # a burn after the last update is never observed
    scores, matched = [], 0
    for i, b in enumerate(burns):
        window_end = float(burns[i + 1]["t_days"]) if i + 1 < len(burns) else math.inf
        score, n = _score_burn(b, window_end, episodes, updates)
        scores.append(score)
        matched += n
    first_burn = float(burns[0]["t_days"]) if burns else math.inf
    false_alarms = sum(1 for x in episodes if x["t"] <= first_burn)
    kept = summary.get("custody_kept")
    return RunManeuverScore(scores, false_alarms, matched - sum(1 for s in scores if s.detected),
                            None if kept is None else bool(kept))


MANEUVER_COLUMNS = ("scenario", "iod", "filter", "delta_v_ms", "response", "runs", "burns", "detected",
                    "p_detect", "p_detect_lo", "p_detect_hi", "next_pass", "p_next_pass", "p_next_pass_lo",
                    "p_next_pass_hi", "two_passes", "p_two_passes", "p_two_passes_lo", "p_two_passes_hi",
                    "median_delay_days", "confirmed", "within_3_sigma", "within_3_sigma_share",
                    "false_alarm_runs", "false_alarm_rate", "false_alarm_lo", "false_alarm_hi",
                    "false_alarms", "repeat_episodes", "custody_kept", "custody_runs")
"""Columns of the report's ``maneuvers.csv``, one row per group."""


def _share(k: int, n: int) -> tuple[float | None, float | None, float | None]:
    """k / n with its Wilson interval; Nones when n is 0."""
    if n < 1:
        return None, None, None
    return (k / n, *wilson_interval(k, n))


def group_maneuver_scores(runs: list[RunManeuverScore]) -> dict[str, Any]:
    """The group's maneuver columns (:data:`MANEUVER_COLUMNS` but the group's names and the
    ``delta_v_ms`` and ``response`` it was run with)."""
    burns = [b for r in runs for b in r.burns]
    detected = [b for b in burns if b.detected]
    nxt = sum(1 for b in detected if b.pass_offset is not None and b.pass_offset <= 0)
    two = sum(1 for b in detected if b.pass_offset is not None and b.pass_offset <= 1)
    errs = [b.dv_error_sigma for b in detected if b.dv_error_sigma is not None]
    within = sum(1 for e in errs if e <= WITHIN_SIGMA)
    fa_runs = sum(1 for r in runs if r.false_alarms > 0)
    judged = [r for r in runs if r.custody_kept is not None]
    out: dict[str, Any] = {"runs": len(runs), "burns": len(burns), "detected": len(detected),
                           "next_pass": nxt, "two_passes": two, "confirmed": len(errs), "within_3_sigma": within,
                           "within_3_sigma_share": within / len(errs) if errs else None,
                           "median_delay_days": float(np.median([b.delay_days for b in detected])) if detected else None,
                           "false_alarm_runs": fa_runs, "false_alarms": sum(r.false_alarms for r in runs),
                           "repeat_episodes": sum(r.repeats for r in runs),
                           "custody_kept": sum(1 for r in judged if r.custody_kept) if judged else None,
                           "custody_runs": len(judged)}
    for name, k in (("p_detect", len(detected)), ("p_next_pass", nxt), ("p_two_passes", two)):
        out[name], out[f"{name}_lo"], out[f"{name}_hi"] = _share(k, len(burns))
    out["false_alarm_rate"], out["false_alarm_lo"], out["false_alarm_hi"] = _share(fa_runs, len(runs))
    return out


def has_maneuvers(summaries: list[dict]) -> bool:
    """Whether any of these run summaries has a truth burn or a detected maneuver."""
    return any(s.get("truth_maneuvers") or s.get("maneuvers") for s in summaries)


DV_SETTING = "truth.maneuvers.delta_v_ms"
RESPONSE_SETTING = "maneuvers.response"


@dataclass(frozen=True)
class GroupRuns:
    """The finished runs of one report group: their summaries (dicts, as in the manifests), their
    steps tables, the sweep combination they were run with and one of their directories."""

    summaries: list[dict]
    tables: list
    sweep: tuple = ()
    out_dir: str | None = None


def _response_of(out_dir: str | None) -> str | None:
    """``[maneuvers] response`` of the scenario a run recorded (``scenario.toml``; "none" by default)."""
    import sys
    from pathlib import Path

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    if out_dir is None or not (Path(out_dir) / "scenario.toml").is_file():
        return None
    try:
        raw = tomllib.loads((Path(out_dir) / "scenario.toml").read_text())
    except (OSError, ValueError):
        return None
    resp = (raw.get("maneuvers") or {}).get("response", "none")
    return str(resp.get("name", "?") if isinstance(resp, dict) else resp)


def _group_delta_v(g: GroupRuns) -> float | None:
    """The group's burn size (m/s): the swept value, else the truth's burns' when they all agree."""
    swept = dict(g.sweep).get(DV_SETTING)
    if swept is not None:
        return float(swept)
    dvs = {round(float(b["delta_v_ms"]), 12) for s in g.summaries for b in s.get("truth_maneuvers") or []
           if _finite(b.get("delta_v_ms")) is not None}
    return dvs.pop() if len(dvs) == 1 else None


def _group_order(item: tuple) -> tuple:
    """Groups by scenario, then by their swept values as values (0.3 before 1 before 10), IOD, filter."""
    (sc, iod, flt), g = item
    base = sc[:sc.index("[")] if g.sweep and "[" in sc else sc
    return base, [(k, isinstance(v, str), v if not isinstance(v, str) else 0, str(v)) for k, v in g.sweep], iod, flt


def maneuver_rows(groups: dict[tuple[str, str, str], GroupRuns]) -> list[dict]:
    """One row per group ((scenario label, iod, filter) -> :class:`GroupRuns`), in key order: the
    group's names, its burn size and response and :func:`group_maneuver_scores`; ``_sweep`` (the
    combination as a dict) and ``_base`` (the scenario's own name) for the figures."""
    rows = []
    for (sc, iod, flt), g in sorted(groups.items(), key=_group_order):
        scores = [score_run(s, update_rows(t)) for s, t in zip(g.summaries, g.tables)]
        sweep = dict(g.sweep)
        resp = sweep.get(RESPONSE_SETTING)
        rows.append({"scenario": sc, "iod": iod, "filter": flt, "delta_v_ms": _group_delta_v(g),
                     "response": str(resp) if resp is not None else _response_of(g.out_dir),
                     **group_maneuver_scores(scores), "_sweep": sweep,
                     "_base": sc[:sc.index("[")] if g.sweep and "[" in sc else sc})
    return rows


def _g(v: Any, spec: str = ".3g") -> str:
    return "-" if v is None else format(v, spec)


def _ratio(k: int | None, n: int, lo: float | None = None, hi: float | None = None) -> str:
    """"k/n [lo-hi]" (the interval when given); "-" when n is 0."""
    if not n or k is None:
        return "-"
    return f"{k}/{n}" + (f" [{lo:.2f}-{hi:.2f}]" if lo is not None and hi is not None else "")


def _cells(r: dict) -> list[str]:
    """A row's cells after its names: burns, detection, timeliness, delay, delta-v, false alarms, custody."""
    n = r["burns"]
    return [str(r["runs"]), str(n), _ratio(r["detected"], n, r["p_detect_lo"], r["p_detect_hi"]),
            _ratio(r["next_pass"], n, r["p_next_pass_lo"], r["p_next_pass_hi"]), _ratio(r["two_passes"], n),
            _g(r["median_delay_days"]), _ratio(r["within_3_sigma"], r["confirmed"]),
            _ratio(r["false_alarm_runs"], r["runs"], r["false_alarm_lo"], r["false_alarm_hi"]),
            _ratio(r["custody_kept"], r["custody_runs"])]


_EXPLAINED = (
    "Per truth burn (a burn after the run's last update is not counted): detected = an episode whose first "
    "detection falls after the burn and before the next burn or the run's end; next pass = that detection "
    "came in the first pass observed after the burn, within 2 passes = in it or the one after; delay = days "
    "from the burn to the first detection; within 3 sigma = the confirmed delta-v estimates with "
    "|dv_est - dv_true| <= 3 sigma. A false alarm is an episode matched to no burn (before the first burn, or "
    "any in a run whose truth does not burn); false alarms = runs with at least one. Intervals: Wilson 95 % "
    "(cistrack.studies.maneuver_scores).")


def maneuver_markdown(rows: list[dict]) -> list[str]:
    """The report's "Maneuvers" section (Markdown lines)."""
    head = ["scenario", "iod", "filter", "runs", "burns", "detected [Wilson 95 %]", "in the next pass [95 %]",
            "within 2 passes", "median delay (d)", "dv within 3 sigma (confirmed)", "false-alarm runs [95 %]",
            "custody kept"]
    out = ["## Maneuvers", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join([r["scenario"], r["iod"], r["filter"], *_cells(r)]) + " |" for r in rows]
    return out + ["", _EXPLAINED, "Every column: maneuvers.csv; figures: maneuver_detection.png (detection "
                  "against delta-v), maneuver_false_alarms.png."]


def maneuver_text(rows: list[dict], width: int = 120) -> list[str]:
    """The "Maneuvers" table for a terminal: per scenario label, one line per filter and IOD (the
    runs are the false alarms' denominator; lines longer than ``width`` are cut with "~")."""
    head = ["filter", "iod", "burns", "detected", "next pass", "<=2 pass", "delay d", "dv 3sig", "false alarms",
            "custody"]
    lines: dict[str, list[list[str]]] = {}
    for r in rows:
        c = _cells(r)
        lines.setdefault(r["scenario"], []).append([r["filter"], r["iod"], c[1], c[2], _ratio(r["next_pass"], r["burns"]),
                                                    *c[4:]])
    every = [c for cells in lines.values() for c in cells]
    widths = [max(len(h), *(len(c[i]) for c in every)) for i, h in enumerate(head)]
    out = []
    for sc, cells in lines.items():
        out.append(f"scenario {sc}:")
        out += ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip() for row in [head, *cells]]
    return (["Maneuvers (detected and false-alarm runs: k/n [Wilson 95 %]; every column: maneuvers.csv):"]
            + [line if len(line) <= width else line[:width - 1] + "~" for line in out])


def write_maneuvers_csv(rows: list[dict], path: Any) -> Any:
    """Write ``maneuvers.csv`` (:data:`MANEUVER_COLUMNS`, one row per group); returns its path."""
    import csv

    from cistrack.results.atomic_files import atomic_target

    with atomic_target(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(MANEUVER_COLUMNS), extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return path
