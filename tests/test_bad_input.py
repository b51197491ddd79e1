"""Bad input, table-driven: every case is either refused clearly or runs correctly.

Each case gives the command line, the files it needs (scenario, study, measurement files), the
environment, and the expected outcome: "refuse" (exit status 2, a ``cistrack: error:`` or usage
message containing the given words, no traceback) or "run" (exit status 0, results written in the
working directory). Every case runs through the real entry point ``cistrack.cli.main`` in a fresh
working directory, and nothing may appear outside it.

Cases come from issue 17's list of failures (sizes, seeds, paths, study options, silent
acceptances, names that became paths), issue 27's (work limits, nesting, epochs, numbers with
underscores, invisible characters in names, files that are not observations) plus the refusals
that already held.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass, field

import pytest

from cistrack.cli.main import main


class Raw(str):
    """A TOML value written as is (for values of the wrong type)."""


def _v(value) -> str:
    if isinstance(value, Raw):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_v(x) for x in value) + "]"
    raise TypeError(value)


BASE = {
    "": {"name": "bad-input", "epoch": "2026-01-01T00:00:00Z", "seed": 1, "duration_days": 1.4},
    "truth": {"orbit": "nrho-9-2"},
    "dynamics": {"name": "cr3bp"},
    "sensor": {"name": "ground-telescope", "measure_range": True},
    "schedule": {"name": "paper-example-1"},
    "iod": {"name": "noisy-range", "n_particles": 200},
    "filter": {"name": "pgm", "n_particles": 200, "n_components": 2},
}
DROP = object()


def scenario(**changes) -> str:
    """The small valid scenario with ``table__key=value`` changes (``top__key`` for the top level;
    DROP removes the key; ``table=None`` removes the table)."""
    tables = {t: dict(kv) for t, kv in BASE.items()}
    for k, v in changes.items():
        if "__" not in k:
            if v is None:
                tables.pop(k, None)
            else:
                tables[k] = v
            continue
        t, key = k.split("__", 1)
        t = "" if t == "top" else t
        tables.setdefault(t, {})
        if v is DROP:
            tables[t].pop(key, None)
        else:
            tables[t][key] = v
    lines = [f"{k} = {_v(v)}" for k, v in tables.pop("").items()]
    for t, kv in tables.items():
        lines.append(f"[{t}]")
        lines += [f"{k} = {_v(v)}" for k, v in kv.items()]
    return "\n".join(lines) + "\n"


STUDY = {"name": "bad-study", "scenarios": ["s.toml"], "filters": ["pgm"], "seeds": [1]}


def study(**changes) -> str:
    d = dict(STUDY)
    for k, v in changes.items():
        if v is DROP:
            d.pop(k, None)
        else:
            d[k] = v
    return "\n".join(f"{k} = {_v(v)}" for k, v in d.items()) + "\n"


CSV_HEAD = "time_utc,azimuth_deg,elevation_deg\n"


def measurements(rows: str, head: str = CSV_HEAD) -> str:
    return head + rows


def meas_scenario() -> str:
    return scenario(truth=None, schedule=None) + '[measurements]\nfile = "obs.csv"\n'


@dataclass
class Case:
    id: str
    argv: list[str]
    expect: str = "refuse"
    words: tuple[str, ...] = ()
    files: dict[str, str | bytes] = field(default_factory=dict)
    env: dict[str, str] = field(default_factory=dict)
    code: int | None = None
    subprocess: bool = False  # run `python -m cistrack.cli.main` (for what a process reads once: kernels)

    def __post_init__(self):
        if self.code is None:
            self.code = 2 if self.expect == "refuse" else 0


def run_case(argv=("s.toml",), words=(), expect="refuse", env=None, **changes) -> dict:
    return dict(argv=["run", *argv, "--quiet"], files={"s.toml": scenario(**changes)}, words=words,
                expect=expect, env=env or {})


CASES: list[Case] = []


def add(id: str, **kw) -> None:
    CASES.append(Case(id=id, **kw))


# -- scenario file: top level ---------------------------------------------------------------------
add("scenario-seed-negative", **run_case(words=("seed", "-1", "2**63-1"), top__seed=-1))
add("scenario-seed-above-2**63", **run_case(words=("seed", "out of range", "2**63-1"), top__seed=Raw(str(2 ** 63))))
add("scenario-seed-string", **run_case(words=("seed",), top__seed="one"))
add("scenario-seed-float", **run_case(words=("seed",), top__seed=1.5))
add("scenario-seed-bool", **run_case(words=("seed",), top__seed=True))
add("scenario-duration-zero", **run_case(words=("duration_days", "> 0"), top__duration_days=0))
add("scenario-duration-negative", **run_case(words=("duration_days", "> 0"), top__duration_days=-3.0))
add("scenario-duration-nan", **run_case(words=("duration_days",), top__duration_days=float("nan")))
add("scenario-duration-inf", **run_case(words=("duration_days",), top__duration_days=float("inf")))
add("scenario-duration-1e9", **run_case(words=("duration_days", "memory", "available"), top__duration_days=1e9))
add("scenario-duration-string", **run_case(words=("duration_days",), top__duration_days="long"))
add("scenario-name-dotdot", **run_case(words=("name", "one path component"), top__name="../../x"))
add("scenario-name-absolute", **run_case(words=("name", "path separator"), top__name="/tmp/x"))
add("scenario-name-slash", **run_case(words=("name", "path separator"), top__name="a/b"))
add("scenario-name-empty", **run_case(words=("name",), top__name=""))
add("scenario-name-dot", **run_case(words=("name",), top__name="."))
add("scenario-name-hidden", **run_case(words=("name", "starts with"), top__name=".hidden"))
add("scenario-name-dash", **run_case(words=("name", "starts with"), top__name="-rf"))
add("scenario-name-newline", **run_case(words=("name", "control"), top__name="a\nb"))
add("scenario-name-backslash", **run_case(words=("name", "separator"), top__name="a\\b"))
add("scenario-name-too-long", **run_case(words=("name", "100 characters"), top__name="x" * 101))
add("scenario-name-number", **run_case(words=("name",), top__name=5))
add("scenario-epoch-garbage", **run_case(words=("epoch", "ISO-8601"), top__epoch="yesterday"))
add("scenario-epoch-number", **run_case(words=("epoch",), top__epoch=5))
add("scenario-unknown-top-key", **run_case(words=("durration_days",), top__durration_days=2.0))
add("scenario-description-number", **run_case(words=("description",), top__description=3))
# -- scenario file: component tables --------------------------------------------------------------
add("filter-n-particles-1e12-float", **run_case(words=("[filter]", "n_particles", "integer"), filter__n_particles=1e12))
add("filter-n-particles-int-1e12", **run_case(words=("n_particles", "memory"), filter__n_particles=10 ** 12))
add("iod-n-particles-1e12", **run_case(words=("[iod]", "n_particles", "memory"), iod__n_particles=10 ** 12))
add("iod-n-particles-1e10", **run_case(words=("[iod]", "n_particles", "memory"), iod__n_particles=10 ** 10))
add("filter-n-particles-negative", **run_case(words=("n_particles",), filter__n_particles=-5))
add("filter-n-particles-zero", **run_case(words=("n_particles",), filter__n_particles=0))
add("filter-n-particles-string", **run_case(words=("n_particles",), filter__n_particles="many"))
add("filter-n-particles-fraction", **run_case(words=("n_particles", "integer"), filter__n_particles=10.5))
add("filter-n-components-above-particles", **run_case(words=("n_components", "n_particles"), filter__n_components=500))
add("filter-n-components-zero", **run_case(words=("n_components",), filter__n_components=0))
add("filter-unknown-name", **run_case(words=("filter", "pgmm"), filter__name="pgmm"))
add("filter-unknown-param", **run_case(words=("filter", "n_partikles"), filter__n_partikles=10))
add("filter-missing-name", **run_case(words=("filter", "name"), filter__name=DROP))
add("filter-table-missing", **run_case(words=("filter",), filter=None))
add("iod-unknown-name", **run_case(words=("iod",), iod__name="guess"))
add("iod-alpha-negative", **run_case(words=("alpha",), iod__name="noisy-range", iod__alpha=-0.1))
add("dynamics-unknown", **run_case(words=("dynamics",), dynamics__name="nbody"))
add("sensor-unknown-param", **run_case(words=("sensor", "colour"), sensor__colour="red"))
add("schedule-unknown", **run_case(words=("schedule",), schedule__name="every-day"))
add("truth-unknown-orbit", **run_case(words=("truth", "orbit"), truth__orbit="nrho-1-1"))
add("truth-orbit-and-state", **run_case(words=("truth", "not both"), truth__state_km=[1.0, 2, 3, 4, 5, 6]))
add("truth-state-short", **run_case(words=("state_km", "6 finite"), truth__orbit=DROP, truth__state_km=[1.0, 2.0]))
add("truth-state-nan", **run_case(words=("state_km", "finite"), truth__orbit=DROP,
                                  truth__state_km=[float("nan"), 0.0, 0.0, 0.0, 1.0, 0.0]))
add("truth-state-strings", **run_case(words=("state_km",), truth__orbit=DROP, truth__state_km=["a"] * 6))
add("truth-missing", **run_case(words=("truth",), truth=None))
add("truth-unknown-key", **run_case(words=("truth", "orbitt"), truth__orbitt="x"))
add("run-predict-every-nan", **run_case(words=("predict_every_hours", "finite"), run__predict_every_hours=float("nan")))
add("run-predict-every-negative", **run_case(words=("predict_every_hours",), run__predict_every_hours=-1.0))
add("run-predict-every-inf", **run_case(words=("predict_every_hours", "finite"), run__predict_every_hours=float("inf")))
add("run-predict-every-string", **run_case(words=("predict_every_hours",), run__predict_every_hours="often"))
add("run-truth-grid-zero", **run_case(words=("truth_grid_minutes",), run__truth_grid_minutes=0))
add("run-truth-grid-huge", **run_case(words=("truth_grid_minutes",), run__truth_grid_minutes=1e6))
add("run-truth-grid-nan", **run_case(words=("truth_grid_minutes",), run__truth_grid_minutes=float("nan")))
add("run-unknown-key", **run_case(words=("[run]", "predict_every"), run__predict_every=2.0))
add("run-end-with-prediction-string", **run_case(words=("end_with_prediction",), run__end_with_prediction="yes"))
add("custody-hdr-threshold-one", **run_case(words=("hdr_threshold",), custody__hdr_threshold=1.0))
add("custody-hdr-consecutive-zero", **run_case(words=("hdr_consecutive",), custody__hdr_consecutive=0))
add("custody-loglik-string", **run_case(words=("loglik_threshold",), custody__loglik_threshold="low"))
add("custody-unknown-key", **run_case(words=("custody",), custody__threshold=1.0))
add("custody-degenerate-ess-negative", **run_case(words=("[custody]", "degenerate_ess", ">= 0"), custody__degenerate_ess=-1.0))
add("custody-collapse-sigma-string", **run_case(words=("[custody]", "collapse_sigma_km"), custody__collapse_sigma_km="tiny"))
add("custody-max-earth-distance-zero", **run_case(words=("[custody]", "max_earth_distance_km", "> 0"),
                                                   custody__max_earth_distance_km=0.0))
# -- scenario file: the file itself ---------------------------------------------------------------
add("scenario-not-toml", argv=["run", "s.toml", "--quiet"], files={"s.toml": "name = = 3\n"}, words=("s.toml", "TOML"))
add("scenario-binary", argv=["run", "s.toml", "--quiet"], files={"s.toml": b"\xff\xfe\x00garbage"}, words=("s.toml",))
add("scenario-empty", argv=["run", "s.toml", "--quiet"], files={"s.toml": ""}, words=("s.toml",))
add("scenario-missing-file", argv=["run", "missing.toml", "--quiet"], words=("missing.toml",))
add("scenario-unknown-builtin", argv=["run", "exampel-1", "--quiet"], words=("exampel-1", "example-1"))
add("scenario-directory", argv=["run", "sub.toml", "--quiet"], files={"sub.toml/x": "x"}, words=("sub.toml",))
# -- command line: run ----------------------------------------------------------------------------
add("flag-seed-negative", **run_case(argv=("s.toml", "--seed", "-1"), words=("--seed", "2**63-1")))
add("flag-seed-above-2**63", **run_case(argv=("s.toml", "--seed", str(2 ** 63)), words=("--seed", "out of range")))
add("flag-seed-huge", **run_case(argv=("s.toml", "--seed", "9" * 40), words=("--seed", "out of range")))
add("flag-seed-word", **run_case(argv=("s.toml", "--seed", "three"), words=("--seed", "invalid int")))
add("flag-seed-float", **run_case(argv=("s.toml", "--seed", "1.5"), words=("--seed", "invalid int")))
add("flag-seed-empty", **run_case(argv=("s.toml", "--seed", ""), words=("--seed",)))
add("flag-seed-missing-value", **run_case(argv=("s.toml", "--seed"), words=("--seed", "expected one argument")))
add("flag-out-existing-file", argv=["run", "s.toml", "--out", "taken", "--quiet"],
    files={"s.toml": scenario(), "taken": "precious"}, words=("--out", "not a directory"))
add("flag-out-foreign-directory", argv=["run", "s.toml", "--out", "docs", "--quiet"],
    files={"s.toml": scenario(), "docs/thesis.tex": "precious"}, words=("--out", "manifest.json"))
add("flag-out-under-a-file", argv=["run", "s.toml", "--out", "taken/sub", "--quiet"],
    files={"s.toml": scenario(), "taken": "precious"}, words=("--out", "cannot write"))
add("flag-unknown", **run_case(argv=("s.toml", "--sead", "3"), words=("unrecognized arguments", "--sead")))
add("flag-max-points-word", **run_case(argv=("s.toml", "--max-points", "all"), words=("--max-points",)))
add("flag-set-malformed", **run_case(argv=("s.toml", "--set", "filter.n_particles"), words=("--set",)))
add("flag-set-unknown-table", **run_case(argv=("s.toml", "--set", "filtre.n_particles=10"), words=("filtre",)))
add("flag-set-bad-value", **run_case(argv=("s.toml", "--set", "filter.n_particles=-3"), words=("n_particles",)))
add("flag-set-seed-negative", **run_case(argv=("s.toml", "--set", "seed=-4"), words=("seed",)))
add("flag-set-name-dotdot", **run_case(argv=("s.toml", "--set", 'name="../up"'), words=("name", "path component")))
add("no-command", argv=[], words=("required",))
add("unknown-command", argv=["fly"], words=("invalid choice",))
# -- environment ----------------------------------------------------------------------------------
add("env-threads-word", **run_case(env={"CISTRACK_NUM_THREADS": "many"}, words=("CISTRACK_NUM_THREADS", "1 to 1024")))
add("env-threads-zero", **run_case(env={"CISTRACK_NUM_THREADS": "0"}, words=("CISTRACK_NUM_THREADS",)))
add("env-threads-negative", **run_case(env={"CISTRACK_NUM_THREADS": "-2"}, words=("CISTRACK_NUM_THREADS",)))
add("env-kernel-dir-is-a-file", **run_case(env={"CISTRACK_KERNEL_DIR": "{tmp}/s.toml"},
                                          words=("kernel cache directory", "not a directory")), subprocess=True)
add("env-kernel-dir-world-writable", argv=["run", "s.toml", "--quiet"], files={"s.toml": scenario(), "kd/.keep": ""},
    env={"CISTRACK_KERNEL_DIR": "{tmp}/kd", "_CHMOD_777": "kd"}, words=("writable by group or others", "chmod 700"),
    subprocess=True)
# -- measurement files ----------------------------------------------------------------------------


def meas_case(csv_text, words, **kw) -> dict:
    files = {"s.toml": meas_scenario()}
    if csv_text is not None:
        files["obs.csv"] = csv_text
    return dict(argv=["run", "s.toml", "--quiet"], files=files, words=words, **kw)


ROW = "2026-01-01T03:40:00Z,101.2,12.3\n"
add("meas-missing-file", **meas_case(None, ("obs.csv",)))
add("meas-empty-file", **meas_case("", ("obs.csv",)))
add("meas-header-only", **meas_case(CSV_HEAD, ("obs.csv",)))
add("meas-missing-column", **meas_case("time_utc,azimuth_deg\n2026-01-01T03:40:00Z,101.2\n", ("obs.csv", "elevation_deg")))
add("meas-azimuth-400", **meas_case(measurements("2026-01-01T03:40:00Z,400.0,12.3\n"), ("obs.csv", "azimuth")))
add("meas-elevation-100", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,100.0\n"), ("obs.csv", "elevation")))
add("meas-azimuth-nan", **meas_case(measurements("2026-01-01T03:40:00Z,nan,12.3\n"), ("obs.csv", "azimuth")))
add("meas-elevation-word", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,high\n"), ("obs.csv", "elevation")))
add("meas-time-garbage", **meas_case(measurements("soon,101.2,12.3\n"), ("obs.csv", "time")))
add("meas-time-not-increasing", **meas_case(measurements(ROW + ROW), ("obs.csv", "time_utc")))
add("meas-too-many-fields", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,12.3,5\n"), ("obs.csv", "fields")))
add("meas-negative-sigma", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,12.3,-1\n",
                                                    "time_utc,azimuth_deg,elevation_deg,sigma_azimuth_arcsec\n"),
                                       ("obs.csv", "sigma")))
add("meas-binary-garbage", **meas_case(b"\x00\x01secret-token-123\xff\xfe\n" * 3, ("obs.csv",)))
add("meas-unknown-site", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,12.3,ZZZ\n",
                                                  "time_utc,azimuth_deg,elevation_deg,site\n"), ("obs.csv", "site")))
# -- study files and flags ------------------------------------------------------------------------


def study_case(words, argv=(), study_text=None, **kw) -> dict:
    return dict(argv=["study", "run", "st.toml", "--quiet", *argv],
                files={"s.toml": scenario(), "st.toml": study_text if study_text is not None else study()},
                words=words, **kw)


add("study-n-seeds-word", **study_case(("n_seeds",), study_text=study(seeds=DROP, n_seeds="three")))
add("study-n-seeds-zero", **study_case(("n_seeds",), study_text=study(seeds=DROP, n_seeds=0)))
add("study-n-seeds-negative", **study_case(("n_seeds",), study_text=study(seeds=DROP, n_seeds=-2)))
add("study-n-seeds-float", **study_case(("n_seeds",), study_text=study(seeds=DROP, n_seeds=2.5)))
add("study-n-seeds-huge", **study_case(("n_seeds",), study_text=study(seeds=DROP, n_seeds=10 ** 12)))
add("study-seeds-negative", **study_case(("seeds", "2**63-1"), study_text=study(seeds=[1, -1])))
add("study-seeds-above-2**63", **study_case(("seeds", "out of range"), study_text=study(seeds=[Raw(str(2 ** 64))])))
add("study-seeds-strings", **study_case(("seeds",), study_text=study(seeds=["a"])))
add("study-seeds-empty", **study_case(("seeds",), study_text=study(seeds=[])))
add("study-seeds-and-n-seeds", **study_case(("not both",), study_text=study(n_seeds=3)))
add("study-name-dotdot", **study_case(("name", "path component"), study_text=study(name="../../escape")))
add("study-name-absolute", **study_case(("name", "path separator"), study_text=study(name="/tmp/escape")))
add("study-label-dotdot", **study_case(("label", "path component"),
                                       study_text=study(filters=[Raw('{ name = "pgm", label = "../../x" }')])))
add("study-label-slash", **study_case(("label", "separator"),
                                      study_text=study(filters=[Raw('{ name = "pgm", label = "a/b" }')])))
add("study-iod-label-dotdot", **study_case(("label",), study_text=study(iod=[Raw('{ name = "noisy-range", label = ".." }')])))
add("study-filter-entry-number", **study_case(("filters",), study_text=study(filters=[3])))
add("study-unknown-filter", **study_case(("filter",), study_text=study(filters=["kalman"])))
add("study-unknown-key", **study_case(("unknown key", "seedz"), study_text=study(seedz=[1])))
add("study-no-scenarios", **study_case(("scenarios",), study_text=study(scenarios=[])))
add("study-missing-scenario", **study_case(("nope.toml",), study_text=study(scenarios=["nope.toml"])))
add("study-not-toml", **study_case(("TOML",), study_text="name = = 1\n"))
add("study-workers-negative", **study_case(("--workers", "out of range"), argv=("--workers", "-1")))
add("study-workers-zero", **study_case(("--workers", "out of range"), argv=("--workers", "0")))
add("study-workers-word", **study_case(("--workers", "invalid int"), argv=("--workers", "two")))
add("study-workers-huge", **study_case(("--workers", "out of range"), argv=("--workers", "100000")))
add("study-n-seeds-flag-zero", **study_case(("--n-seeds", "out of range"), argv=("--n-seeds", "0")))
add("study-first-seed-flag-negative", **study_case(("--first-seed", "2**63-1"), argv=("--first-seed", "-5")))
add("study-first-seed-flag-word", **study_case(("--first-seed", "invalid int"), argv=("--first-seed", "one")))
add("study-first-seed-key-string", **study_case(("first_seed",), study_text=study(seeds=DROP, n_seeds=2, first_seed="a")))
add("study-seeds-and-first-seed", **study_case(("not both",), study_text=study(first_seed=3)))
add("study-last-seed-above-2**63", **study_case(("last seed",), argv=("--first-seed", str(2 ** 63 - 1), "--n-seeds", "2")))
add("study-missing-file", argv=["study", "run", "nope.toml", "--quiet"], words=("nope",))
add("study-report-missing", argv=["study", "report", "nope.toml"], words=("nope",))
# -- other commands -------------------------------------------------------------------------------
add("plugins-unknown", argv=["plugins", "--check", "no-such-thing"], words=("no-such-thing",))
add("plugins-param-malformed", argv=["plugins", "--check", "pgm", "--param", "n_particles"], words=("--param", "KEY=VALUE"))
add("export-missing-run", argv=["export", "no-run"], words=("no-run",))
add("export-out-exists", argv=["export", "no-run", "--out", "e.oem"], files={"e.oem": "an earlier export\n"},
    words=("--out", "e.oem", "already exists", "--overwrite"))
add("rerun-file-exists", argv=["run", "s.toml", "--rerun", "rec.rrd", "--quiet"],
    files={"s.toml": scenario(), "rec.rrd": b"RRF2 an earlier recording"}, words=("rec.rrd", "already exists", "--overwrite"))
add("rerun-file-is-a-link", argv=["run", "s.toml", "--rerun", "rec.rrd", "--quiet"],
    files={"s.toml": scenario(), "_LINK rec.rrd": "elsewhere.rrd"}, words=("rec.rrd", "already exists"))
# -- issue 27: up-front limits on work ------------------------------------------------------------
add("run-predict-every-1e-7", **run_case(words=("[run]", "predict_every_hours", "3.36e+08 filter steps", "1,000,000"),
                                         run__predict_every_hours=1e-7))
add("schedule-interval-1e-6", **run_case(words=("[schedule]", "interval_minutes", "measurement times", "1,000,000"),
                                         schedule={"name": "every", "interval_minutes": 1e-6}))
add("schedule-phase-interval-1e-6", **run_case(words=("[schedule]", "phases[0].interval_minutes", "1,000,000"),
                                               schedule={"name": "phased", "phases": [
                                                   Raw('{ rule = "every", interval_minutes = 1e-6 }')]}))
add("schedule-count-1e9", **run_case(words=("[schedule]", "count", "1,000,000"),
                                     schedule={"name": "random-consecutive", "count": 10 ** 9}))
OBS_LATE = "2030-01-01T03:40:00Z,101.2,12.3\n"
add("meas-years-after-the-span", **meas_case(measurements(ROW + OBS_LATE),
                                             ("obs.csv", "outside the scenario's span", "duration_days", "1,461")))
add("meas-before-the-epoch", **meas_case(measurements("2025-12-01T03:40:00Z,101.2,12.3\n" + ROW),
                                         ("obs.csv", "outside the scenario's span", "epoch")))
# -- issue 27: deeply nested TOML -----------------------------------------------------------------


def nested(n: int) -> Raw:
    return Raw("[" * n + "]" * n)


add("scenario-nested-3000", **run_case(words=("s.toml", "nested", "16 levels"), filter__clusterer=nested(3000)))
add("scenario-nested-400", **run_case(words=("s.toml", "nested", "16 levels"), filter__clusterer=nested(400)))
add("scenario-nested-tables-3000", argv=["run", "s.toml", "--quiet"],
    files={"s.toml": scenario() + "[run]\nx = " + "{a = " * 3000 + "1" + "}" * 3000 + "\n"}, words=("s.toml", "nested"))
add("scenario-dotted-keys-3000", argv=["run", "s.toml", "--quiet"],
    files={"s.toml": scenario() + "[" + ".".join(["t"] * 3000) + "]\nx = 1\n"}, words=("s.toml", "nested"))
add("flag-set-nested-3000", **run_case(argv=("s.toml", "--set", "filter.n_particles=" + nested(3000)),
                                       words=("--set", "nested", "16 levels")))
add("study-nested-3000", **study_case(("st.toml", "nested", "16 levels"), study_text=study(filters=[nested(3000)])))
# -- issue 27: epochs -----------------------------------------------------------------------------
add("epoch-9999-12-31", **run_case(words=("top level", "epoch", "1800-01-01 to 2200-01-01"), top__epoch="9999-12-31T00:00:00Z"))
add("epoch-0001-01-01", **run_case(words=("top level", "epoch", "1800-01-01 to 2200-01-01"), top__epoch="0001-01-01T00:00:00Z"))
add("epoch-span-ends-after-2200", **run_case(words=("epoch", "duration_days", "2200-01-01"), top__epoch="2199-12-31T12:00:00Z"))
add("real-telescope-epoch-1800", **run_case(words=("[sensor]", "epoch", "DE421", "1900 to 2052"),
                                            sensor={"name": "real-telescope"}, top__epoch="1800-01-01T00:00:00Z"))
add("real-telescope-epoch-2060", **run_case(words=("[sensor]", "epoch", "DE421", "1900 to 2052"),
                                            sensor={"name": "real-telescope"}, top__epoch="2060-01-01T00:00:00Z"))
# -- issue 27: numbers, names, files, sizes -------------------------------------------------------
add("meas-azimuth-underscores", **meas_case(measurements("2026-01-01T03:40:00Z,1_01.2,12.3\n"),
                                            ("obs.csv", "azimuth", "not a number")))
add("meas-range-underscores", **meas_case(measurements("2026-01-01T03:40:00Z,101.2,12.3,3_84000\n",
                                                       "time_utc,azimuth_deg,elevation_deg,range_km\n"),
                                          ("obs.csv", "range_km", "not a number")))
add("env-threads-underscores", **run_case(env={"CISTRACK_NUM_THREADS": "1_0"}, words=("CISTRACK_NUM_THREADS", "1 to 1024")))
add("env-numba-threads-zero", **run_case(env={"NUMBA_NUM_THREADS": "0"}, words=("NUMBA_NUM_THREADS", "at least 1")),
    subprocess=True)
add("scenario-name-rtl-override", **run_case(words=("name", "U+202E"), top__name="evil\u202ecod.exe"))
add("scenario-name-zero-width", **run_case(words=("name", "U+200B"), top__name="a\u200bb"))
add("study-name-rtl-override", **study_case(("name", "U+202E"), study_text=study(name="st\u202eudy")))
add("study-label-rtl-override", **study_case(("label", "U+2067"),
                                             study_text=study(filters=[Raw('{ name = "pgm", label = "p\\u2067gm" }')])))
add("meas-bom-csv-header-read", **meas_case("\ufeff" + measurements("2026-01-01T03:40:00Z,400.0,12.3\n"),
                                            ("obs.csv", "line 2", "azimuth")))


def meas_file_case(file: str, words, files=None) -> dict:
    return dict(argv=["run", "s.toml", "--quiet"], words=words,
                files={"s.toml": scenario(truth=None, schedule=None) + f'[measurements]\nfile = "{file}"\n', **(files or {})})


add("meas-file-dot", **meas_file_case(".", ("[measurements]", "file", "is a directory")))
add("meas-file-directory", **meas_file_case("obs", ("obs", "is a directory"), {"obs/a.csv": CSV_HEAD}))
add("meas-file-passwd", **meas_file_case("passwd", ("passwd", "not an observation file of any known format"),
                                         {"passwd": "root:x:0:0:root:/root:/bin/bash\n"}))
add("iod-n-particles-1", **run_case(words=("[iod]", "n_particles", ">= 100", "collapsed"), iod__n_particles=1))
add("truth-state-3e6-km", **run_case(words=("[truth]", "state_km", "km from Earth"), truth__orbit=DROP,
                                     truth__state_km=[3e6, 0.0, 0.0, 0.0, 1.0, 0.0]))
add("study-seeds-repeat", **study_case(("seeds", "repeats seed(s) 1"), study_text=study(seeds=[1, 1])))
# -- inputs that must run correctly ---------------------------------------------------------------
add("ok-small-scenario", **run_case(expect="run"))
add("ok-seed-zero-flag", **run_case(argv=("s.toml", "--seed", "0"), expect="run"))
add("ok-seed-max-flag", **run_case(argv=("s.toml", "--seed", str(2 ** 63 - 1)), expect="run"))
add("ok-name-with-spaces", **run_case(expect="run", top__name="my case 1"))
add("ok-rerun-overwrite", argv=["run", "s.toml", "--rerun", "rec.rrd", "--overwrite", "--quiet"],
    files={"s.toml": scenario(), "rec.rrd": b"RRF2 an earlier recording"}, expect="run")
add("ok-enkf-filter-without-components", **run_case(expect="run", filter__name="enkf", filter__n_components=DROP))


def _materialise(case: Case, tmp) -> None:
    for name, content in case.files.items():
        if name.startswith("_LINK "):  # a dangling symbolic link: name -> content
            (tmp / name[len("_LINK "):]).symlink_to(content)
            continue
        p = tmp / name
        p.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_clearly_or_runs(case: Case, tmp_path, monkeypatch, capsys):
    work = tmp_path / "work"
    work.mkdir()
    _materialise(case, work)
    monkeypatch.chdir(work)
    for k, v in case.env.items():
        if k == "_CHMOD_777":
            (work / v).chmod(0o777)
            continue
        monkeypatch.setenv(k, v.format(tmp=work))
    before = sorted(os.listdir(tmp_path))
    if case.subprocess:
        proc = subprocess.run([sys.executable, "-m", "cistrack.cli", *case.argv], capture_output=True, text=True,
                              env=dict(os.environ), cwd=work)
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    else:
        try:
            code = main(list(case.argv))
        except SystemExit as exc:  # argparse usage errors
            code = exc.code
        out, err = capsys.readouterr()
    assert sorted(os.listdir(tmp_path)) == before, "something was written outside the working directory"
    assert "Traceback" not in err + out
    assert code == case.code, f"exit status {code}; stderr: {err}"
    if case.expect == "refuse":
        assert "error" in err.lower(), err
        for w in case.words:
            assert w.lower() in err.lower(), f"{w!r} not in: {err}"
    else:
        assert any((work / "runs").iterdir())


def test_the_table_has_at_least_100_cases():
    assert len(CASES) >= 100
    assert len({c.id for c in CASES}) == len(CASES)
