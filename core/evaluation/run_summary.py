"""The typed summary of one run, shared by the run, the CLI, the results store and studies.

On disk (``manifest.json`` key ``summary``) it is :meth:`RunSummary.to_dict`: the flat keys
earlier versions wrote (``custody_kept``, ``custody_lost_step``, ...) plus ``verdict``;
:meth:`RunSummary.from_dict` reads both forms, so studies resume over old run directories.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack.propagation.impulses import BURN_LINES, burns_summary
from cistrack.evaluation.custody import VERDICT_KINDS, Verdict

__all__ = ["RunSummary", "RECORDED_VERDICT_KINDS", "FINAL_KEYS", "summarize", "count_lines", "final_lines", "maneuver_lines"]

FINAL_KEYS: tuple[str, ...] = (
    "sigma_x_km", "sigma_y_km", "sigma_z_km", "sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms",
    "pos_err_km", "vel_err_ms", "nees", "entropy", "truth_loglik", "hdr_level", "bound_pos_km")
"""Metrics reported for the last update and at the end of each pass."""


@dataclass
class RunSummary:
    """What a run ended with.

    Attributes
    ----------
    run_id : str
    seed : int
    status : str                 "finished" or "filter-failed"
    failure : str                the error that stopped the filter ("" if none)
    verdict : Verdict            final verdict (kind, reason, step, t_days): tracking,
                                 not-converged, lost, diverged, filter-failed or no-truth
    has_truth : bool             whether the run had a truth (without one: no custody, ever)
    n_steps, n_updates, n_measurements : int
    n_passes : int               visibility passes of the sensor over the run (observed or not:
                                 a sensor shutoff or the schedule leaves some unobserved)
    n_passes_observed : int      passes with at least one measurement
    n_measurements_before_iod : int   measurements at or before the IOD epoch (the IOD's own
                                 input: not filter updates)
    consistency : dict           measurement consistency of the updates
                                 (:func:`cistrack.evaluation.residuals.consistency_summary`: mean NIS and
                                 its chi-square bounds, share outside 95 %, largest residual)
    final : dict                 FINAL_KEYS of the last update (or the last step), km, m/s, cm/s
    pass_end : dict              pass number (str) -> FINAL_KEYS and t_days at its last update
    wall_time_s, prepare_time_s : float   seconds of the run and of its preparation (truth,
                                 measurements, IOD), compilation excluded
    compile_time_s : float       seconds numba spent compiling during the run (0 with a warm kernel
                                 cache; ~1 min for a model's first run on a new machine)
    maneuvers : list of dict     each maneuver detected (:mod:`cistrack.runs.maneuver_watch`):
                                 t_days, t_burn_days, delta_v_ms, delta_v_sigma_ms, confirmed, ...
    truth_maneuvers : list of dict   the truth's burns: t_days, delta_v_ms (magnitude, m/s),
                                 delta_v_vector_ms (synodic components), label
    """

    run_id: str
    seed: int
    status: str = "finished"
    failure: str = ""
    verdict: Verdict = field(default_factory=Verdict)
    has_truth: bool = True
    n_steps: int = 0
    n_updates: int = 0
    n_measurements: int = 0
    n_passes: int = 0
    n_passes_observed: int = 0
    n_measurements_before_iod: int = 0
    consistency: dict[str, Any] = field(default_factory=dict)
    final: dict[str, float] = field(default_factory=dict)
    pass_end: dict[str, dict[str, float]] = field(default_factory=dict)
    wall_time_s: float = 0.0
    prepare_time_s: float = 0.0
    compile_time_s: float = 0.0
    maneuvers: list[dict[str, Any]] = field(default_factory=list)
    truth_maneuvers: list[dict[str, Any]] = field(default_factory=list)

    @property
    def custody_kept(self) -> bool:
        return self.verdict.kept

    @property
    def custody_lost_step(self) -> int | None:
        return self.verdict.step

    @property
    def custody_lost_t_days(self) -> float | None:
        return self.verdict.t_days

    @property
    def ended_normally(self) -> bool:
        """Whether the run ran to its end ("finished"): only then is ``final`` the end of the run;
        a run whose filter raised holds the state before it raised, which a study's final-state
        calibration and efficiency leave out."""
        return self.status == "finished"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (the manifest's ``summary``)."""
        custody = {} if not self.has_truth else {  # no truth: no custody to speak of
            "custody_kept": self.custody_kept, "custody_lost_step": self.custody_lost_step,
            "custody_lost_t_days": self.custody_lost_t_days}
        return {
            "run_id": self.run_id, "seed": self.seed, "status": self.status, "failure": self.failure,
            **custody, "verdict": self.verdict.to_dict(), "has_truth": self.has_truth,
            "n_steps": self.n_steps, "n_updates": self.n_updates, "n_measurements": self.n_measurements,
            "n_passes": self.n_passes, "n_passes_observed": self.n_passes_observed,
            "n_measurements_before_iod": self.n_measurements_before_iod,
            "consistency": dict(self.consistency), "final": dict(self.final), "pass_end": dict(self.pass_end),
            "wall_time_s": self.wall_time_s, "prepare_time_s": self.prepare_time_s,
            "compile_time_s": self.compile_time_s,
            "maneuvers": [dict(m) for m in self.maneuvers], "truth_maneuvers": [dict(m) for m in self.truth_maneuvers],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "RunSummary":
        """Inverse of :meth:`to_dict`; also reads summaries written before ``verdict`` existed.
        ValueError saying what is missing when ``data`` is not a run summary (a damaged manifest)."""
        _check_summary(data)
        verdict = _recorded_verdict(data["verdict"]) if "verdict" in data else _verdict_before_kinds(data)
        names = ("n_steps", "n_updates", "n_measurements", "n_passes", "n_passes_observed",
                 "n_measurements_before_iod", "consistency", "final", "pass_end", "wall_time_s", "prepare_time_s", "compile_time_s",
                 "status", "failure", "maneuvers", "truth_maneuvers")
        has_truth = bool(data.get("has_truth", verdict.kind != "no-truth"))  # older manifests: from the verdict
        return cls(run_id=data["run_id"], seed=int(data["seed"]), verdict=verdict, has_truth=has_truth,
                   **{k: data[k] for k in names if k in data})


RECORDED_VERDICT_KINDS: tuple[str, ...] = (*VERDICT_KINDS, "none")
"""The verdict kinds a run's summary holds: the final ones, and "none" for a run that did not finish."""


def _recorded_verdict(data: Any) -> Verdict:
    """The :class:`Verdict` of a summary's ``verdict`` table; ValueError when it is not a table
    (null included) or its kind is not one a run records: never a verdict the run did not have."""
    if not isinstance(data, dict):
        raise ValueError(f"its verdict is {json.dumps(data, default=str)}, not a table, so the run's verdict is unknown")
    if data.get("kind") not in RECORDED_VERDICT_KINDS:
        raise ValueError(f"its verdict kind {data.get('kind')!r} is not one a run records "
                         f"({', '.join(RECORDED_VERDICT_KINDS)})")
    return Verdict.from_dict(data)


def _verdict_before_kinds(data: dict[str, Any]) -> Verdict:
    """The verdict of a summary written before ``verdict`` existed, from its flat custody keys."""
    if data.get("custody_kept", True):
        return Verdict()
    failed = data.get("status") == "filter-failed"
    return Verdict("filter-failed" if failed else "lost", data.get("failure", "") if failed else "",
                   data.get("custody_lost_step"), data.get("custody_lost_t_days"))


def _check_summary(data: Any) -> None:
    """ValueError unless ``data`` is a run summary: a JSON object with a text ``run_id`` and an
    integer ``seed``."""
    if not isinstance(data, dict):
        raise ValueError(f"not a run summary (a JSON {type(data).__name__}, not an object)")
    if not isinstance(data.get("run_id"), str):
        raise ValueError(f"not a run summary: its 'run_id' is {data.get('run_id')!r}, not a text")
    seed = data.get("seed")
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise ValueError(f"not a run summary: its 'seed' is {seed!r}, not an integer")


def summarize(run, rows: list[dict[str, Any]], verdict: Verdict, status: str, failure: str,
              wall_time_s: float, prepare_time_s: float, compile_time_s: float = 0.0) -> RunSummary:
    """The summary of ``run`` (a RunContext) from its table ``rows`` (see :func:`step_row`)."""
    updates = [r for r in rows if r["kind"] == "update"]
    last = updates[-1] if updates else (rows[-1] if rows else {})
    pass_end: dict[str, dict[str, float]] = {}
    for r in updates:
        p = int(r.get("pass_index", 0))
        if p > 0:
            pass_end[str(p)] = {k: r[k] for k in FINAL_KEYS if k in r} | {"t_days": r["t_days"]}
    from cistrack.evaluation.residuals import consistency_summary

    times = [float(m.t) for m in run.measurements]
    observed = sum(1 for p in run.passes if any(p.start <= t <= p.end for t in times))
    before_iod = sum(1 for t in times if t <= float(run.iod_cloud.epoch) + 1e-12)  # as the run's events
    return RunSummary(
        run_id=run.run_id, seed=int(run.seed), status=status, failure=failure, verdict=verdict,
        has_truth=run.truth is not None, n_steps=len(rows), n_updates=len(updates),
        n_measurements=len(run.measurements), n_passes=len(run.passes), n_passes_observed=observed,
        n_measurements_before_iod=before_iod,
        consistency=consistency_summary(rows), final={k: last[k] for k in FINAL_KEYS if k in last},
        pass_end=pass_end, wall_time_s=wall_time_s, prepare_time_s=prepare_time_s, compile_time_s=compile_time_s,
        truth_maneuvers=[_truth_burn(i) for i in getattr(run, "truth_impulses", None) or ()])


def _truth_burn(impulse) -> dict[str, Any]:
    """A truth impulse (:class:`cistrack.interfaces.maneuvers.Impulse`) as a ``truth_maneuvers`` entry."""
    from cistrack import units

    dv = np.asarray(impulse.dv, dtype=float) * float(units.vu_to_kms(1.0)) * 1000.0
    return {"t_days": float(units.tu_to_days(impulse.t)), "delta_v_ms": float(np.linalg.norm(dv)),
            "delta_v_vector_ms": [float(v) for v in dv], "label": impulse.label}


def count_lines(s: RunSummary) -> list[str]:
    """What the run's counts mean, in words: measurements, the passes they fall in (of the
    sensor's visibility passes: a schedule or a sensor shutoff leaves some unobserved), the
    measurements the IOD used and the filter updates after it."""
    passes = ""
    if s.n_passes:
        unobserved = s.n_passes - s.n_passes_observed
        passes = (f" in {s.n_passes_observed} of {s.n_passes} visibility passes"
                  + (f" ({unobserved} unobserved: schedule or sensor shutoff)" if unobserved else ""))
    updates = (f"{s.n_measurements_before_iod} up to the IOD epoch (the IOD's input), {s.n_updates} filter "
               "updates after it" if s.n_measurements_before_iod else f"{s.n_updates} filter updates")
    return [f"  {s.n_measurements} measurements{passes}", f"  {updates}, wall time {s.wall_time_s:.1f} s"
            + (f" (and {s.compile_time_s:.1f} s compiling, once per machine)" if s.compile_time_s >= 0.05 else "")]


def maneuver_lines(s: RunSummary) -> list[str]:
    """The truth's burns and the maneuvers the run detected (``summary.maneuvers``), one line
    each: when detected, and the burn's least-squares estimate (m/s, days since the epoch) or
    why there is none. No lines for a ballistic run without detections."""
    burns = s.truth_maneuvers
    lines = ([f"  truth burn: {b['delta_v_ms']:.3g} m/s at {b['t_days']:.3f} d" for b in burns] if len(burns) <= BURN_LINES
             else ["  " + burns_summary([b["t_days"] for b in burns], [b["delta_v_ms"] for b in burns])])
    for k, m in enumerate(s.maneuvers, 1):
        head = f"  maneuver {k}: detected at {m['t_days']:.3f} d"
        if m.get("confirmed"):
            lines.append(f"{head}; burn {m['delta_v_ms']:.3g} +- {m['delta_v_sigma_ms']:.2g} m/s at "
                         f"{m['t_burn_days']:.3f} +- {m.get('t_burn_sigma_days') or 0.0:.2g} d")
        elif m.get("confirmed") is None:
            lines.append(f"{head}; not estimated ([maneuvers] estimate = false)")
        elif m.get("unconfirmed_reason"):
            lines.append(f"{head}; unconfirmed: {m['unconfirmed_reason']}")
        else:
            lines.append(f"{head}; unconfirmed: the least squares kept no burn there")
    return lines


_SIGMA_POS = ("sigma_x_km", "sigma_y_km", "sigma_z_km")
_SIGMA_VEL = ("sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms")
_CMS_TO_MS = 0.01


def final_lines(final: dict[str, float], fmt) -> list[str]:
    """The final metrics (:attr:`RunSummary.final`) in words, positions in km and every velocity in
    m/s (the stored per-axis velocity sigmas, cm/s, converted), the units said in a header line;
    ``fmt`` formats one number (None as "-"). No lines without metrics."""
    if not final:
        return []

    def ms(key: str) -> float | None:
        v = final.get(key)
        return None if v is None else float(v) * _CMS_TO_MS

    lines = ["  final state (positions in km, velocities in m/s):",
             "    per-axis sigma: position " + " / ".join(fmt(final.get(k)) for k in _SIGMA_POS) + " km, velocity "
             + " / ".join(fmt(ms(k)) for k in _SIGMA_VEL) + " m/s"]
    if "pos_err_km" in final:
        lines.append(f"    error: position {fmt(final['pos_err_km'])} km, velocity {fmt(final.get('vel_err_ms'))} m/s, "
                     f"NEES {fmt(final.get('nees'))}, entropy {fmt(final.get('entropy'))}")
    return lines
