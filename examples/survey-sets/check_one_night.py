"""One site's night of survey sets, fitted alone: how the fit and its sky predictions hold.

    .venv/bin/python examples/survey-sets/check_one_night.py SETS_DIR OUT_DIR

For each set of ``make_survey_sets.py`` in SETS_DIR, its first two nights of one site spanning at
least 1.5 hours with at least 6 observations (the injected outliers dropped) are each written to
OUT_DIR/<set>-n<k>.psv and fitted with ``cistrack fit`` (no option). For a converged fit, one JSON
line gives the position error and the Mahalanobis distance squared (6-D) of the truth at the fit
epoch under fit.json's covariance (times its noise scale squared when above 1), and, for the
set's next observation at least 12 hours later, the squared Mahalanobis distance of its RA/Dec
under ``cistrack predict``'s sky covariance at its site and time (inside the 3-sigma ellipse: at
most 9). Lines go to stdout and all of them to OUT_DIR/results.json.
"""
import csv
import json
import subprocess
import sys
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.fitting.fit_export import covariance_scale
from cistrack.plugin.registry import default_registry
from cistrack.runs.export import scenario_of

PY = sys.executable


def _utc(text: str) -> datetime:
    return datetime.fromisoformat(text.replace("Z", "+00:00"))


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    """(the two header lines, the data rows split on |) of an ADES PSV file."""
    lines = path.read_text().splitlines()
    return lines[:2], [ln.split("|") for ln in lines[2:] if ln.strip()]


def _nights(rows: list[list[str]]) -> list[list[list[str]]]:
    """Runs of one site's rows without an 8-hour gap, spanning >= 1.5 h with >= 6 rows."""
    groups, cur = [], [rows[0]]
    for r in rows[1:]:
        if r[2] == cur[-1][2] and _utc(r[3]) - _utc(cur[-1][3]) < timedelta(hours=8):
            cur.append(r)
        else:
            groups.append(cur)
            cur = [r]
    groups.append(cur)
    return [g for g in groups if _utc(g[-1][3]) - _utc(g[0][3]) >= timedelta(hours=1.5) and len(g) >= 6]


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-m", "cistrack.cli", *args], capture_output=True, text=True)


def _truth_score(d: Path, truth_csv: Path, rec: dict) -> dict:
    """Position error (km) and 6-D Mahalanobis^2 of the truth at the fit epoch."""
    reg = default_registry()
    scen = scenario_of(d, reg)
    dyn = scen.build("dynamics", reg)
    tr = list(csv.reader(ln for ln in truth_csv.read_text().splitlines() if not ln.startswith("#")))[1:]
    ts = np.array([units.utc_to_tu(scen.epoch, units.parse_utc(r[0])) for r in tr])
    i = int(np.argmin(np.abs(ts - rec["epoch_tu"])))
    x = units.state_from_km(np.array([float(v) for v in tr[i][1:]]))
    xt = units.state_to_km(dyn.propagate(x[None], ts[i], np.array([rec["epoch_tu"]])).states[0, 0])
    e = xt - np.array(rec["state_km"])
    cov = np.array(rec["covariance_km"]) * covariance_scale(rec)
    return {"err_km": float(np.linalg.norm(e[:3])), "m2": float(e @ np.linalg.solve(cov, e))}


def _sky_score(d: Path, obs: list[str], night_end: str) -> dict:
    """Sky Mahalanobis^2 of the observation ``obs`` under predict's covariance at its site and time."""
    q = _cli("predict", str(d), "--site", obs[2], "--start", obs[3], "--stop", obs[3], "--quiet", "--out", str(d / "next"))
    if q.returncode != 0:
        return {"predict_fail": (q.stdout + q.stderr)[-300:]}
    s = next(csv.DictReader(open(d / "next.csv")))
    ra, dec = float(s["ra_deg"]), float(s["dec_deg"])
    dd = np.array([((float(obs[4]) - ra + 180) % 360 - 180) * np.cos(np.radians(dec)), float(obs[5]) - dec]) * 3600
    a, b = float(s["semi_major_1sigma_arcsec"]), float(s["semi_minor_1sigma_arcsec"])
    pa = np.radians(float(s["position_angle_deg"]))
    u, v = np.array([np.sin(pa), np.cos(pa)]), np.array([np.cos(pa), -np.sin(pa)])
    return {"sky_m2": float((dd @ u / a) ** 2 + (dd @ v / b) ** 2), "sky_miss_arcsec": float(np.linalg.norm(dd)),
            "sky_3a": 3 * a, "dt_days": (_utc(obs[3]) - _utc(night_end)).total_seconds() / 86400}


def _one(sd: Path, name: str, head: list[str], night: list[list[str]], rows: list[list[str]], out: Path) -> dict:
    f = out / f"{name}.psv"
    f.write_text("\n".join(head + ["|".join(r) for r in night]) + "\n")
    d = out / name
    p = _cli("fit", str(f), "--out", str(d), "--quiet", "--overwrite")
    row = {"name": name, "code": p.returncode, "n": len(night)}
    if not (d / "fit.json").is_file():
        return row
    rec = json.loads((d / "fit.json").read_text())
    lv = rec.get("line_of_variations") or {}
    row.update(converged=rec["converged"], minima=len(lv.get("minima", [])), linear=lv.get("linear"),
               better=any(m.startswith("a better solution") for m in rec.get("messages", [])),
               horizon=(rec.get("determination") or {}).get("horizon_days"))
    if not rec["converged"]:
        return row
    row.update(_truth_score(d, sd / "truth.csv", rec))
    later = [r for r in rows if _utc(r[3]) > _utc(night[-1][3]) + timedelta(hours=12)]
    if later:
        row.update(_sky_score(d, later[0], night[-1][3]))
    return row


def main() -> int:
    sets, out = Path(sys.argv[1]), Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    res = []
    for sd in sorted(p for p in sets.iterdir() if (p / "set.json").is_file()):
        bad = {(o["utc"], o["site"]) for o in json.loads((sd / "set.json").read_text())["outliers"]}
        head, rows = _rows(sd / "observations.psv")
        rows = [r for r in rows if (r[3], r[2]) not in bad]
        for k, night in enumerate(_nights(rows)[:2]):
            res.append(_one(sd, f"{sd.name}-n{k}", head, night, rows, out))
            print(json.dumps(res[-1]), flush=True)
    (out / "results.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
