"""Fit survey-cadence sets with `cistrack fit` (no option) and tabulate how the fits did.

    .venv/bin/python examples/survey-sets/check_survey_fit.py SET_DIR [SET_DIR ...] [--out DIR]

Each SET_DIR holds ``observations.psv`` and ``truth.csv`` (``make_survey_sets.py``; its
``set.json`` names the injected outliers, if any). For each: ``cistrack fit SET_DIR/observations.psv
--out OUT/<name>`` and ``cistrack export OUT/<name> --format oem``, then one row:

- format (of the observation file), method (the IOD and filter ``fit.json`` names), outcome;
- position error at the fit epoch (the last observation), km;
- largest Mahalanobis distance squared of the truth under the exported OEM covariance over the
  OEM's epochs inside the arc (bound 22.5: chi-square, 6 degrees of freedom, 99.9 %);
- observations in the fit (used or rejected: ``residuals.csv``) of those in the file (a fit of
  the latest arc only leaves the others out);
- post-fit RMS (arcsec, both angles, observations used), outliers rejected / injected, clean
  observations rejected (the rest of the rejections), and the wall time of the fit (s);
- for a set whose object made a burn (``make_survey_sets.py --burn-ms``; ``set.json`` ``burn``):
  the burns ``fit.json`` reports, and for the one nearest the truth's time its time's z-score,
  its magnitude's and the vector's Mahalanobis distance squared (3 dof; 14.2 at 99.7 %). The truth
  after the burn is propagated from the first ``truth.csv`` row after it (a fit with the burn
  exports the orbit after it only). A burn the fit missed is shown with the largest burn that
  ``fit.json``'s ``burn_sensitivity`` says its gap hides ("disclosed" when that covers it).

The truth is the first row of ``truth.csv`` propagated with the fit's own dynamics and mapped
into the OEM's frame with the export's transform, as ``examples/real-data/check_fit.py`` does.
Exit status 0 when every set converged with Mahalanobis^2 <= 22.5 at every arc epoch, all
injected outliers rejected and at most ``max_clean_rejected`` clean observations rejected (one,
or 5 % of them if more: at the 3-sigma chi-square threshold a clean observation is rejected with
probability 0.3 %) and every observation of the file in the fit, and, for a burn of 0.3 m/s or
more, one burn reported with its time and magnitude within 3 sigma of the truth (no burn for a
set without one); 1 otherwise.
"""
from __future__ import annotations

import argparse
import csv
import importlib.util
import json
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cistrack import units

MAHALANOBIS2_BOUND = 22.5  # chi-square, 6 degrees of freedom, 99.9 % (22.46)
_HERE = Path(__file__).resolve().parent


def _read_oem():
    """``read_oem`` of examples/real-data/check_fit.py (one OEM reader for both checkers)."""
    spec = importlib.util.spec_from_file_location("check_fit", _HERE.parent / "real-data" / "check_fit.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.read_oem


@dataclass
class Row:
    """One data set's line of the table."""

    name: str
    format: str = ""
    method: str = ""
    outcome: str = ""
    error_km: float = float("nan")
    max_m2: float = float("nan")
    rms_arcsec: float = float("nan")
    rejected_injected: int = 0
    injected: int = 0
    rejected: int = 0
    seconds: float = float("nan")
    failure: str = ""
    m2: list = field(default_factory=list)

    n_observations: int = 0
    n_fitted: int = 0
    burn_ms: float = 0.0
    burns: str = "-"
    burn_ok: bool = True

    @property
    def clean_rejected(self) -> int:
        return self.rejected - self.rejected_injected

    @property
    def max_clean_rejected(self) -> int:
        return max(1, round(0.05 * (self.n_observations - self.injected)))

    @property
    def ok(self) -> bool:
        return (self.outcome == "converged" and self.max_m2 <= MAHALANOBIS2_BOUND
                and self.rejected_injected == self.injected and self.clean_rejected <= self.max_clean_rejected
                and self.n_fitted == self.n_observations and self.burn_ok)


def run_cli(*args: str) -> tuple[int, float, str]:
    """``cistrack ARGS`` in a subprocess: (exit status, wall seconds, output)."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True)
    return proc.returncode, time.perf_counter() - t0, proc.stdout + proc.stderr


def _truth_rows(truth_csv: Path) -> list[list[str]]:
    return [r for r in csv.reader(ln for ln in truth_csv.read_text().splitlines() if not ln.startswith("#"))][1:]


def _truth_in_oem_frame(fit_dir: Path, truth_csv: Path, epochs: list[str], burn_utc: str | None = None,
                        area_to_mass: float = 0.0) -> tuple[np.ndarray, np.ndarray, object]:
    """(OEM times TU, truth states in the OEM frame (K, 6) km, km/s, truth_at function): the truth
    propagated with the fit's dynamics, with the truth's own ``area_to_mass`` (m^2/kg; set.json's
    ``area_to_mass_m2_kg``, 0 when absent) whatever the fit estimated, from the first
    ``truth.csv`` row, and after ``burn_utc`` (a burn) from the first row after it."""
    from cistrack.fitting.fit_export import _scenario
    from cistrack.least_squares.trajectory import arc_states
    from cistrack.plugin.registry import default_registry

    reg = default_registry()
    scen = _scenario(fit_dir, reg)
    dyn = scen.build("dynamics", reg)
    if area_to_mass:  # the fit's scenario flies none: a set made with radiation pressure carries its own
        dyn = dyn.with_parameters(area_to_mass_m2_kg=area_to_mass)
    frame = scen.build("sensor", reg).inertial_frame()
    rows = _truth_rows(truth_csv)
    anchors = [rows[0]] + ([next(r for r in rows if units.parse_utc(r[0]) > units.parse_utc(burn_utc))]
                           if burn_utc else [])
    starts = [(units.utc_to_tu(scen.epoch, units.parse_utc(r[0])), units.state_from_km(np.array([float(v) for v in r[1:]])))
              for r in anchors]
    t_burn = units.utc_to_tu(scen.epoch, units.parse_utc(burn_utc)) if burn_utc else np.inf

    def truth_at(t: np.ndarray) -> np.ndarray:
        out = np.empty((len(t), 6))
        after = t >= t_burn
        for k, part in enumerate((~after, after)):
            if np.any(part):
                out[part] = arc_states(dyn, starts[k][1], starts[k][0], t[part])
        return out

    t = np.array([units.utc_to_tu(scen.epoch, units.parse_utc(e + "Z")) for e in epochs])
    return t, frame.from_synodic(truth_at(t), t), truth_at


def _hidden_in_gap(rec: dict, burn: dict) -> str:
    """'' or, for a burn the fit missed, what ``fit.json``'s ``burn_sensitivity`` says of its gap:
    the largest burn there the observations would not show."""
    t = units.parse_utc(burn["utc"])
    for gap in (rec.get("burn_sensitivity") or {}).get("gaps", []):
        if units.parse_utc(gap["start_utc"]) < t < units.parse_utc(gap["end_utc"]):
            size = gap["largest_hidden_ms"]
            bound = "any size" if size is None else f"{size:.0f} m/s" if size >= 10 else f"{size:.2g} m/s"
            return f" (its gap hides {bound}: {'disclosed' if size is None or size >= burn['delta_v_ms'] else 'showable'})"
    return ""


def _score_burn(row: Row, rec: dict, burn: dict | None) -> None:
    """The row's ``burns`` and ``burn_ok`` from fit.json's ``maneuvers`` against the set's ``burn``."""
    found = rec.get("maneuvers") or []
    row.burn_ms = float(burn["delta_v_ms"]) if burn else 0.0
    if not burn:
        row.burns, row.burn_ok = (f"{len(found)} spurious" if found else "none"), not found
        return
    if not found:
        row.burns, row.burn_ok = "missed" + _hidden_in_gap(rec, burn), row.burn_ms < 0.3
        return
    t_true = units.parse_utc(burn["utc"])
    m = min(found, key=lambda e: abs((units.parse_utc(e["t_burn_utc"]) - t_true).total_seconds()))
    z_t = (units.parse_utc(m["t_burn_utc"]) - t_true).total_seconds() / 86400.0 / max(m["t_burn_sigma_days"], 1e-12)
    z_dv = (m["delta_v_ms"] - row.burn_ms) / max(m["delta_v_sigma_ms"], 1e-12)
    d = np.asarray(m["delta_v_vector_ms"]) - np.asarray(burn["delta_v_vector_ms"])
    m2 = float(d @ np.linalg.solve(np.asarray(m["delta_v_covariance_ms2"]), d))
    row.burns = (f"{len(found)}: {m['delta_v_ms']:.3g} +- {m['delta_v_sigma_ms']:.2g} m/s, time z {z_t:+.1f}, "
                 f"size z {z_dv:+.1f}, vector M^2 {m2:.1f}")
    row.burn_ok = len(found) == 1 and abs(z_t) <= 3 and abs(z_dv) <= 3 or row.burn_ms < 0.3


def _score(row: Row, fit_dir: Path, truth_csv: Path, info: dict) -> None:
    """Fill the row's error, Mahalanobis, RMS, rejections and burns from a converged, exported fit
    (``info``: the set's set.json)."""
    outliers, burn = info.get("outliers", []), info.get("burn")
    rec = json.loads((fit_dir / "fit.json").read_text())
    _score_burn(row, rec, burn)
    epochs, states, covs = _read_oem()(fit_dir / "estimate.oem")
    t, truth, truth_at = _truth_in_oem_frame(fit_dir, truth_csv, epochs, burn["utc"] if burn else None,
                                             float(info.get("area_to_mass_m2_kg", 0.0)))
    m2 = np.array([float((truth[k] - states[k]) @ np.linalg.solve(covs[k], truth[k] - states[k]))
                   for k in range(len(t))])
    arc = t <= rec["arc"]["last_tu"] + 600.0 / units.TU_S
    row.m2 = m2[arc].tolist()
    row.max_m2 = float(m2[arc].max())
    e = units.state_to_km(truth_at(np.array([rec["epoch_tu"]]))[0]) - np.asarray(rec["state_km"])
    row.error_km = float(np.linalg.norm(e[:3]))
    with (fit_dir / "residuals.csv").open() as fh:
        res = list(csv.DictReader(fh))
    used = [r for r in res if r["rejected"] == "false"]
    both = np.array([float(r[k]) for r in used for k in ("ra_cos_dec_arcsec", "dec_arcsec")])
    row.rms_arcsec = float(np.sqrt(np.mean(both ** 2)))
    rejected = {(r["utc"][:19], r["site"]) for r in res if r["rejected"] == "true"}
    row.rejected = len(rejected)
    row.n_fitted = len(res)
    row.rejected_injected = sum((o["utc"][:19], o["site"]) in rejected for o in outliers)


def check_set(set_dir: Path, out: Path) -> Row:
    """Fit, export and score one set; the row says what happened."""
    row = Row(set_dir.name, format="ADES PSV")
    info = json.loads((set_dir / "set.json").read_text()) if (set_dir / "set.json").is_file() else {}
    outliers = info.get("outliers", [])
    row.injected = len(outliers)
    row.n_observations = int(info.get("n_observations", 0))
    fit_dir = out / set_dir.name
    rc, row.seconds, text = run_cli("fit", str(set_dir / "observations.psv"), "--out", str(fit_dir))
    rec = json.loads((fit_dir / "fit.json").read_text()) if (fit_dir / "fit.json").is_file() else {}
    filt = rec.get("filter") or {}
    row.method = (f"{filt['iod']} + {filt.get('name', '?')} + least squares" if filt.get("iod")
                  else "none (refused before the IOD)")
    if rc != 0 or not rec.get("converged"):
        row.outcome = "failed"
        lines = text.strip().splitlines()
        row.failure = rec.get("failure") or "; ".join(rec.get("messages", [])[:1]) or (lines[-1] if lines else f"exit {rc}")
        return row
    row.outcome = "converged"
    rc, _s, text = run_cli("export", str(fit_dir), "--format", "oem")
    if rc != 0:
        row.outcome, row.failure = "export failed", text.strip()[-300:]
        return row
    _score(row, fit_dir, set_dir / "truth.csv", info)
    return row


def table(rows: list[Row]) -> str:
    """Markdown table of the rows (failures listed below it)."""
    out = ["| data set | obs. fitted / in file | format | method | outcome | error at last obs. (km) | max M^2 (<= 22.5) "
           "| RMS (\") | outliers rejected / injected | clean rejected | burns reported | time (s) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r.name} | {r.n_fitted} / {r.n_observations} | {r.format} | {r.method} | {r.outcome} | {r.error_km:.2f} | "
                   f"{r.max_m2:.2f} | {r.rms_arcsec:.3f} | {r.rejected_injected} / {r.injected} | {r.clean_rejected} | "
                   f"{r.burns} | {r.seconds:.1f} |")
    out += [f"- {r.name}: {r.failure}" for r in rows if r.failure]
    return "\n".join(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sets", type=Path, nargs="+")
    ap.add_argument("--out", type=Path, default=Path("runs/survey-fits"))
    a = ap.parse_args()
    rows = [check_set(s, a.out) for s in a.sets]
    print(table(rows))
    return 0 if all(r.ok for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
