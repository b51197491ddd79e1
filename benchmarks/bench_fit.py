"""CPU time of ``cistrack fit`` per observation file, and how far the fitted orbit moved.

Each file is fitted by a fresh ``cistrack fit FILE --out DIR --quiet`` process (exec to exit:
start-up, the numba kernel-cache load, the run, the plots); its CPU time is the process's user +
system time (``resource.getrusage(RUSAGE_CHILDREN)``), so a busy machine inflates it less than the
wall clock. A reference CPU time comes from ``cistrack run example-1 --quiet`` the same way.

``--save FILE`` keeps each fit's CPU time, state and covariance (``fit.json``) as JSON;
``--before FILE`` compares with such a file: the "before" column, and the state difference
Mahalanobis-normalised by the new fit's covariance (sqrt(d^T P^-1 d), d in km and km/s).

    .venv/bin/python benchmarks/bench_fit.py FILE [FILE ...] [--save before.json] [--before before.json]
    .venv/bin/python benchmarks/bench_fit.py --make-arc /tmp/arc3      # then fit /tmp/arc3/observations.psv
    .venv/bin/python benchmarks/bench_fit.py --make-dense /tmp/dense    # 24,000 observations, 12 tracklets
    PYTHONPATH=/tmp/old-tree .venv/bin/python benchmarks/bench_fit.py FILE ... --save before.json

(the second form measures another copy of the package, e.g. the commit before a change;
``--repeat N``: N processes per file, the least CPU time kept and the median saved as
``cpu_median_s``).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402


ROOT = Path(__file__).resolve().parents[1]
ARC_SITES = ("711", "809", "G96")


def make_arc(directory: Path) -> Path:
    """A 319-observation arc of three sites over ten nights: the built-in 'real-data' campaign
    simulated twice (examples/real-data/make_observations.py, seeds 7 and 8, the second 6 minutes
    later) for MPC 711, 809 and G96 over 10 days, merged into ``directory/observations.psv``."""
    from cistrack.fitting.observation_input import read_object_observations, write_merged
    from cistrack.plugin.registry import default_registry

    make = ROOT / "examples" / "real-data" / "make_observations.py"
    parts = []
    for seed, start in ((7, 0.0), (8, 0.1)):
        part = directory / f"part-{seed}"
        subprocess.run([sys.executable, str(make), "--out", str(part), "--days", "10", "--sites", *ARC_SITES,
                        "--seed", str(seed), "--start-hours", str(start)], check=True, stdout=subprocess.DEVNULL)
        parts.append(str(part / "observations.psv"))
    reg = default_registry()
    [obs] = read_object_observations(parts, reg, {}, lambda m: None)
    write_merged(directory / "observations", obs.measurements, obs.designation, reg)
    return directory / "observations.psv"


def make_dense(directory: Path, per: int = 2000, seed: int = 146, family: str = "dro") -> Path:
    """The survey set ``family`` seed ``seed`` (examples/survey-sets/make_survey_sets.py: its nights,
    sites and noise) with each tracklet resampled to ``per`` exposures over its span, written to
    ``directory/observations.psv``: 12 tracklets, 24,000 observations for the defaults."""
    import importlib.util

    from cistrack.astro.site_network import merge_sites
    from cistrack.plugin.registry import default_registry
    from cistrack.runs.observation_files import write_observations

    spec = importlib.util.spec_from_file_location("mss", ROOT / "examples" / "survey-sets" / "make_survey_sets.py")
    mss = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mss)
    streams = np.random.SeedSequence([seed, mss.FAMILIES.index(family)]).spawn(5)
    choose, plan, noise = (np.random.default_rng(s) for s in streams[:3])
    reg = default_registry()
    _info, scen, dyn, x0, times = mss._draw(family, seed, (choose, plan), reg)
    parts = []
    for code, tracklets in times.items():
        t = np.sort(np.concatenate([np.linspace(tr[0], tr[-1], per) for tr in tracklets]))
        sensor, site = mss._sensor(scen, reg, code)
        parts.append((code, site, sensor.simulate(dyn.propagate(x0[None], 0.0, t).states[:, 0, :], t, noise)))
    ms = merge_sites(parts)
    ms.meta["object"] = f"dense{family}"
    directory.mkdir(parents=True, exist_ok=True)
    write_observations(directory / "observations.psv", ms, scen.epoch, format="ades-psv")
    return directory / "observations.psv"


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(cmd: list[str]) -> tuple[float, float, int]:
    """(CPU s, wall s, exit status) of one process running ``cmd``."""
    c0, w0 = _children_cpu(), time.perf_counter()
    rc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=os.environ.copy()).returncode
    return _children_cpu() - c0, time.perf_counter() - w0, rc


def _cistrack() -> list[str]:
    return [sys.executable, "-m", "cistrack.cli"]


def fit_one(path: str, work: Path, repeat: int = 1) -> dict:
    """Fit ``path`` in ``repeat`` fresh processes: the least CPU s (and its wall s), exit status,
    observations, state, covariance. ``path``: one file, or several joined by "+" (fitted
    together, as ``cistrack fit A B`` does)."""
    out = work / f"fit-{abs(hash(path))}"
    runs = []
    for _ in range(max(1, repeat)):
        shutil.rmtree(out, ignore_errors=True)
        runs.append(_timed(_cistrack() + ["fit", *path.split("+"), "--out", str(out), "--quiet"]))
    cpu, wall, rc = min(runs)
    row = {"file": path, "cpu_s": cpu, "cpu_median_s": float(np.median([r[0] for r in runs])), "wall_s": wall,
           "rc": rc}
    fit = out / "fit.json"
    if fit.exists():
        data = json.loads(fit.read_text())
        row.update(_state_of(data))
    return row


def _state_of(data: dict) -> dict:
    """State (km, km/s), its 6x6 covariance and the observation count from a fit.json."""
    out: dict = {}
    for key in ("state_km", "state"):
        if key in data:
            out["state"] = np.asarray(data[key], dtype=float).ravel()[:6].tolist()
            break
    for key in ("covariance_km", "covariance"):
        if key in data:
            out["covariance"] = np.asarray(data[key], dtype=float)[:6, :6].tolist()
            break
    out["n"] = int(data.get("n_used", 0)) + int(data.get("n_rejected", 0))
    out["epoch"] = data.get("epoch_utc", data.get("epoch"))
    return out


def mahalanobis(new: dict, old: dict) -> float:
    """sqrt(d^T P^-1 d): the state difference in units of the new fit's covariance (nan if missing)."""
    if "state" not in new or "state" not in old or "covariance" not in new or new.get("epoch") != old.get("epoch"):
        return float("nan")
    d = np.asarray(new["state"]) - np.asarray(old["state"])
    p = np.asarray(new["covariance"])
    return float(np.sqrt(max(d @ np.linalg.solve(p, d), 0.0)))


def reference_cpu(work: Path, repeat: int = 1) -> float:
    """The least CPU s of ``repeat`` ``cistrack run example-1 --quiet`` processes (the reference)."""
    out = work / "example-1"
    best = float("inf")
    for _ in range(max(1, repeat)):
        shutil.rmtree(out, ignore_errors=True)
        best = min(best, _timed(_cistrack() + ["run", "example-1", "--quiet", "--out", str(out)])[0])
    return best


def _label(path: str) -> str:
    """The file's name with its folder (``a3/observations.psv``), files joined by "+"."""
    return "+".join("/".join(Path(p).parts[-2:]) for p in path.split("+"))[-34:]


def _table(rows: list[dict], before: dict, ref: float) -> list[str]:
    lines = [f"{'file':34s} {'obs':>5s} {'CPU before':>10s} {'CPU after':>10s} {'x example-1':>11s} "
             f"{'shift/sigma':>11s} {'rc':>3s}"]
    for r in rows:
        old = before.get(r["file"], {})
        cpu_old = f"{old['cpu_s']:10.2f}" if "cpu_s" in old else f"{'-':>10s}"
        shift = mahalanobis(r, old) if old else float("nan")
        lines.append(f"{_label(r['file']):34s} {r.get('n', 0):5d} {cpu_old} {r['cpu_s']:10.2f} "
                     f"{r['cpu_s'] / ref:11.2f} {shift:11.3f} {r['rc']:3d}")
    lines.append(f"reference: cistrack run example-1 --quiet, CPU {ref:.2f} s")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--make-arc", metavar="DIR", help="write the 3-site, 10-night arc (make_arc) into DIR and stop")
    ap.add_argument("--make-dense", metavar="DIR", help="write 12 tracklets of 2,000 exposures (make_dense) into DIR "
                    "and stop")
    ap.add_argument("--save", help="write the fits' CPU times, states and covariances to this JSON file")
    ap.add_argument("--before", help="compare with a JSON file written by --save")
    ap.add_argument("--no-reference", action="store_true", help="skip the cistrack run example-1 reference")
    ap.add_argument("--repeat", type=int, default=1, help="processes per file (and reference): the least CPU time")
    args = ap.parse_args(argv)
    if args.make_arc:
        print(f"wrote {make_arc(Path(args.make_arc))}")
        return 0
    if args.make_dense:
        print(f"wrote {make_dense(Path(args.make_dense))}")
        return 0
    before = {r["file"]: r for r in json.loads(Path(args.before).read_text())["rows"]} if args.before else {}
    with tempfile.TemporaryDirectory(prefix="bench-fit-") as tmp:
        work = Path(tmp)
        ref = float("nan") if args.no_reference else reference_cpu(work, args.repeat)
        rows = [fit_one(f, work, args.repeat) for f in args.files]
    for line in machine_lines():
        print(line)
    for line in _table(rows, before, ref):
        print(line)
    if args.save:
        Path(args.save).write_text(json.dumps({"reference_cpu_s": ref, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
