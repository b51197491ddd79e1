"""A run end to end through the CLI: results written as it goes, reproducible for a seed."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

import numpy as np
import pytest

from cistrack.results.run_status import run_status
from cistrack.results.store import read_manifest, read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


def _quick(**over):
    return load_scenario("quick").with_overrides({"duration_days": 1.4, **over})


def _numbers(rows):
    """The rows without wall-clock timings (``time_*_s``), which differ between any two runs."""
    return [{k: v for k, v in r.items() if not k.startswith("time_")} for r in rows]


def test_same_scenario_and_seed_give_the_same_numbers():
    s = _quick(filter={"n_particles": 300, "n_components": 2}, iod={"n_particles": 300})
    a = run_scenario(s, seed=5).rows
    b = run_scenario(s, seed=5).rows
    assert _numbers(a) == _numbers(b)


def test_different_filters_see_the_same_measurements():
    s = _quick(filter={"n_particles": 300, "n_components": 2}, iod={"n_particles": 300})
    r1 = run_scenario(s, seed=2)
    r2 = run_scenario(s.with_overrides({"filter": {"name": "enkf"}}), seed=2)
    np.testing.assert_array_equal(r1.context.measurements.values, r2.context.measurements.values)


def test_cli_run_writes_manifest_and_table_and_counts_what_it_used(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "custody:" in proc.stdout
    man = read_manifest(out)
    assert man["status"] == "finished" and man["seed"] == 1
    t = read_steps(out)
    assert t.num_rows == man["summary"]["n_steps"]
    assert {"entropy", "pos_err_km", "sigma_vx_cms", "nees", "custody"} <= set(t.column_names)
    s = man["summary"]
    assert (f"{s['n_measurements']} measurements in {s['n_passes_observed']} of {s['n_passes']} visibility passes"
            in proc.stdout)
    assert (f"{s['n_measurements_before_iod']} up to the IOD epoch (the IOD's input), {s['n_updates']} filter "
            "updates after it" in proc.stdout)
    assert s["n_measurements_before_iod"] + s["n_updates"] == s["n_measurements"]   # one site: one update each
    iod = [line for line in proc.stderr.splitlines() if "IOD '" in line]
    assert len(iod) == 1 and "measurements of pass 1 (of " in iod[0], proc.stderr


def test_cli_quiet_run_with_settings_prints_nothing_and_runs_the_settings(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), "--quiet",
                           "--set", "filter.n_particles=400", "--set", "duration_days=1.2"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert (proc.stdout, proc.stderr) == ("", "")
    ran = tomllib.loads((out / "scenario.toml").read_text())
    assert ran["filter"]["n_particles"] == 400 and ran["duration_days"] == 1.2


@pytest.mark.parametrize("setting, named", [("filter.n_particles=-5", "n_particles"),
                                            ("filter.n_particle=5", "n_particle"),
                                            ("filter", "TABLE.KEY=VALUE")])
def test_cli_run_refuses_a_bad_setting_naming_the_key(tmp_path, setting, named):
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(tmp_path / "r"),
                           "--set", setting], capture_output=True, text=True)
    assert proc.returncode == 2
    assert named in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "r").exists()


def test_a_run_killed_mid_way_leaves_a_readable_partial_table(tmp_path):
    out = tmp_path / "killed"
    env = dict(os.environ)
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), "--quiet",
                             "--rows-per-part", "1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    deadline = time.time() + 240
    while time.time() < deadline:
        parts = list((out / "steps").glob("part-*.parquet")) if (out / "steps").exists() else []
        if len(parts) >= 3 or proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert len(parts) >= 3, "the run did not get three steps in"
    t = read_steps(out)
    assert t.num_rows >= 3
    assert read_manifest(out)["status"] == "running"
    status, reason = run_status(out)  # the manifest's process is gone: read as interrupted
    assert status == "interrupted" and "process gone" in reason and str(proc.pid) in reason
    assert list(t.column("step").to_pylist()) == sorted(t.column("step").to_pylist())


def test_cli_reports_a_bad_scenario_without_a_traceback(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('[dynamics]\nname = "cr3bq"\n[sensor]\nname="ground-telescope"\n[iod]\nname="noisy-range"\n[filter]\nname="pgm"\n')
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", str(p)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "Did you mean 'cr3bp'" in proc.stderr and str(p) in proc.stderr


def test_cli_scenarios_lists_builtin_scenarios_and_studies():
    out = subprocess.run([sys.executable, "-m", "cistrack.cli", "scenarios"], capture_output=True, text=True,
                         check=True).stdout
    assert "example-1" in out and "Paper Example 1" in out
    assert "filter-comparison" in out and "PGM vs UKF" in out


def test_the_summary_counts_passes_without_measurements_as_unobserved():
    """A schedule that observes the first pass only: the later visibility passes are counted, and
    said to be unobserved (as during a sensor shutoff), not passed off as observed."""
    from cistrack.evaluation.run_summary import count_lines
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    scen = load_scenario("quick").with_overrides({
        "duration_days": 3.0, "schedule": {"name": "phased", "phases": [{"rule": "every", "interval_minutes": 40.0,
                                                                          "to_pass": 1}]}})
    res = run_scenario(scen, seed=1)
    s, ctx = res.summary, res.context
    times = [m.t for m in ctx.measurements]
    observed = [p for p in ctx.passes if any(p.start <= t <= p.end for t in times)]
    assert s.n_passes == len(ctx.passes) > s.n_passes_observed == len(observed) >= 1
    unobserved = s.n_passes - s.n_passes_observed
    assert (f"{s.n_measurements} measurements in {len(observed)} of {s.n_passes} visibility passes "
            f"({unobserved} unobserved: schedule or sensor shutoff)") in count_lines(s)[0]


def test_a_target_that_never_sets_is_refused_with_the_reason():
    """With the elevation mask at -90 deg the target is in view for the whole run: its one pass is
    in progress at t = 0 and is never tasked. The error says so, not only "0 visibility passes"."""
    from cistrack.errors import ConfigError
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    scen = load_scenario("quick").with_overrides({"sensor": {"elevation_mask_deg": -90.0}})
    with pytest.raises(ConfigError, match=r"the whole run: the target does not set within it\) is never tasked"):
        run_scenario(scen, seed=1)


def test_a_run_shorter_than_a_tenth_of_an_hour_states_its_pass_in_seconds():
    """duration_days = 1e-6 had said '(0.0 h, the whole run: the target never sets)' (probe H13)."""
    from cistrack.errors import ConfigError
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    scen = load_scenario("quick").with_overrides({"duration_days": 1e-6})
    with pytest.raises(ConfigError, match=r"the pass in progress at t = 0 \(0\.0864 s, the whole run: the target "
                                          r"does not set within it\)"):
        run_scenario(scen, seed=1)
