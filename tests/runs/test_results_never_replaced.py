"""A run never replaces results it was not asked to replace (issue 50).

- A run with ``--set`` items and no ``--out`` writes to a default directory that names them (as a
  study's default directory does), not over the plain run's.
- A run into a directory that holds the results of another scenario, other settings or another
  seed is refused, naming the directory, what is there and the ways out; ``--overwrite`` replaces
  them; the same run again replaces its own results as before.
- Two runs on one results directory at once: the second is refused at once, naming the directory
  and the first's process, and the first finishes with its results intact.
- A ``--rerun`` recording path that is one of the run's own result files (or inside its part
  folders) is refused, naming both paths.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.results.output_paths import RUN_LOCK
from cistrack.results.store import read_steps
from cistrack.runs.run_id import scenario_run_id
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import settings_suffix

SHORT = ["--set", "duration_days=1.4"]


def _run(*args: str) -> int:
    return main(["run", "quick", "--quiet", *args])


def _manifest(d: Path) -> dict:
    return json.loads((d / "manifest.json").read_text())


def test_a_run_with_set_items_gets_its_own_default_directory(tmp_path, monkeypatch):
    from cistrack.studies.study import _settings_suffix

    monkeypatch.chdir(tmp_path)
    assert _run("--set", "duration_days=1.4") == 0
    assert _run("--set", "duration_days=1.3") == 0
    plain = scenario_run_id(load_scenario("quick"), 1)
    names = sorted(p.name for p in (tmp_path / "runs").iterdir())
    assert names == sorted([plain + settings_suffix(["duration_days=1.4"]),
                            plain + settings_suffix(["duration_days=1.3"])])
    assert all(n.startswith(plain + "__set-") and len(n) == len(plain) + 14 for n in names)
    assert _settings_suffix(["duration_days=1.4"]) == settings_suffix(["duration_days=1.4"])  # one helper
    assert settings_suffix(None) == settings_suffix([]) == ""


def test_another_settings_results_are_not_replaced_without_overwrite(tmp_path, capsys):
    out = tmp_path / "r"
    assert _run("--out", str(out), "--set", "duration_days=1.4") == 0
    before, table = _manifest(out), (out / "steps.parquet").read_bytes()
    capsys.readouterr()
    assert _run("--out", str(out), "--set", "duration_days=1.3") == 2
    err = capsys.readouterr().err
    assert str(out) in err and "'quick'" in err and "seed 1" in err and "duration_days" in err
    assert "1.4" in err and "1.3" in err and "--overwrite" in err and "another --out" in err
    assert _manifest(out) == before and (out / "steps.parquet").read_bytes() == table
    assert _run("--out", str(out), "--set", "duration_days=1.3", "--overwrite") == 0
    assert _manifest(out)["fingerprint"] != before["fingerprint"]


def test_another_seed_is_refused_and_the_same_run_again_replaces_its_own(tmp_path, capsys):
    out = tmp_path / "r"
    assert _run("--out", str(out), *SHORT) == 0
    first = _manifest(out)
    capsys.readouterr()
    assert _run("--out", str(out), *SHORT, "--seed", "2") == 2
    err = capsys.readouterr().err
    assert str(out) in err and "seed: 1 there, 2 now" in err
    assert _manifest(out) == first
    assert _run("--out", str(out), *SHORT) == 0  # the same scenario, settings and seed: replaced as before
    again = _manifest(out)
    assert again["fingerprint"] == first["fingerprint"] and again["started_unix"] > first["started_unix"]


def test_a_directory_left_with_only_the_lock_file_takes_a_run(tmp_path):
    out = tmp_path / "r"
    out.mkdir()
    (out / RUN_LOCK).write_text("12345 on elsewhere\n")  # a run killed before its manifest was written
    assert _run("--out", str(out), *SHORT) == 0
    assert _manifest(out)["status"] == "finished"


@pytest.mark.skipif(sys.platform == "win32", reason="SIGSTOP/SIGCONT")
def test_a_second_run_on_one_directory_is_refused_while_the_first_writes(tmp_path):
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "cistrack.cli", "run", "quick", "--quiet", "--out", str(out), *SHORT]
    first = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        deadline = time.monotonic() + 120
        while not ((out / RUN_LOCK).is_file() and (out / RUN_LOCK).read_text().startswith(f"{first.pid} ")):
            assert first.poll() is None, first.communicate()
            assert time.monotonic() < deadline, "the first run never took the lock"
            time.sleep(0.01)
        os.kill(first.pid, signal.SIGSTOP)  # the first run holds the lock, mid-run
        try:
            t0 = time.monotonic()
            second = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=120)
            waited = time.monotonic() - t0
        finally:
            os.kill(first.pid, signal.SIGCONT)
        assert second.returncode == 2, second.stderr
        assert str(out) in second.stderr and f"process {first.pid} on" in second.stderr
        assert "another 'cistrack run'" in second.stderr and "Traceback" not in second.stderr
        assert waited < 60  # refused at once, not after waiting for the first
        _, err = first.communicate(timeout=300)
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    assert first.returncode == 0, err
    man = _manifest(out)
    assert man["status"] == "finished" and man["process"]["pid"] == first.pid
    assert read_steps(out).num_rows > 0 and not any((out / "steps").glob("part-*.parquet"))


@pytest.mark.parametrize("recording", ["steps.parquet", "manifest.json", "estimates.parquet", "scenario.toml",
                                       "steps/part-0.rrd", "estimates-parts/x.rrd", "estimate.oem", "."])
def test_a_recording_over_the_runs_own_results_is_refused(tmp_path, capsys, recording):
    out = tmp_path / "r"
    assert _run("--out", str(out), *SHORT) == 0
    files = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    path = str(out / recording) if recording != "." else str(out)
    assert _run("--out", str(out), *SHORT, "--rerun", path) == 2
    err = capsys.readouterr().err
    assert f"--rerun {path}:" in err and f"results directory {out}" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == files


def test_a_recording_inside_a_new_directorys_part_folder_is_refused_before_it_is_made(tmp_path, capsys):
    out = tmp_path / "new"
    assert _run("--out", str(out), *SHORT, "--rerun", str(out / "steps" / "rec.rrd")) == 2
    assert "part files" in capsys.readouterr().err and not out.exists()


def test_a_recording_path_the_system_refuses_is_refused_before_the_run(tmp_path, capsys):
    out = tmp_path / "r"
    path = tmp_path / ("x" * 300 + ".rrd")  # longer than a file name may be: the folder is writable, the file not
    assert _run("--out", str(out), *SHORT, "--rerun", str(path)) == 2
    err = capsys.readouterr().err
    assert f"--rerun {path}: cannot write there" in err and "Traceback" not in err and not out.exists()


def test_another_programs_manifest_is_not_taken_for_an_earlier_run(tmp_path, capsys):
    web = tmp_path / "webapp"
    web.mkdir()
    (web / "manifest.json").write_text('{"name": "My PWA", "start_url": "/index.html"}')
    (web / "index.html").write_text("<html>")
    assert main(["run", "quick", "--out", str(web), "--quiet", "--set", "duration_days=1.5"]) == 2
    assert "holds no cistrack manifest.json" in capsys.readouterr().err
    assert json.loads((web / "manifest.json").read_text())["name"] == "My PWA"
