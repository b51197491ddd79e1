"""`cistrack export` writes only the estimate of a run that finished and did not diverge, unless
--force, and then the file says why in a COMMENT; a full disk never leaves a partial file, and a
run that failed on a full disk never prints result paths that do not exist (issue 27, items 2
and 5). Real runs: a finished one, a failed one, a diverged one (the bootstrap particle filter
on the quick scenario's first pass) and a CLI run that is stopped, then killed with SIGKILL."""
from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.plugin.hookspecs import hookimpl
from cistrack.results.store import read_manifest
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SMALL = {"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2}, "iod": {"n_particles": 300}}
SMALL_SET = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
             "--set", "iod.n_particles=300"]


class FailsAtStep:
    """An observer (as a third-party recorder would be) that raises when step ``k`` is updated."""

    def __init__(self, k: int):
        self.k = k

    @hookimpl
    def cistrack_step_updated(self, run, step):
        if step.index >= self.k:
            raise OSError(28, "No space left on device")


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("runs")
    run_scenario(load_scenario("quick").with_overrides(SMALL), seed=1, output_dir=d / "finished")
    run_scenario(load_scenario("quick").with_overrides(SMALL), seed=1, output_dir=d / "failed",
                 observers=[FailsAtStep(3)])
    sir = {"duration_days": 1.4, "filter": {"name": "sir", "n_particles": 300}, "iod": {"n_particles": 300}}
    run_scenario(load_scenario("quick").with_overrides(sir), seed=1, output_dir=d / "diverged")
    assert read_manifest(d / "finished")["status"] == "finished"
    assert read_manifest(d / "finished")["summary"]["verdict"]["kind"] != "diverged"
    assert read_manifest(d / "failed")["status"] == "failed"
    assert read_manifest(d / "diverged")["summary"]["verdict"]["kind"] == "diverged"
    return {p.name: p for p in d.iterdir()}


def _warning(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if line.startswith("COMMENT WARNING")]


@pytest.mark.parametrize("fmt", ["oem", "opm"])
def test_a_finished_run_exports_without_a_warning(runs, tmp_path, fmt, capsys):
    out = tmp_path / f"x.{fmt}"
    assert main(["export", str(runs["finished"]), "--format", fmt, "--out", str(out)]) == 0
    assert out.is_file() and _warning(out) == []


@pytest.mark.parametrize("case, why", [("failed", "did not finish (status 'failed'"),
                                       ("diverged", "its filter diverged (degenerate weights")])
def test_a_failed_or_diverged_run_is_refused_unless_force_and_then_the_file_says_so(runs, tmp_path, case, why, capsys):
    out = tmp_path / "x.oem"
    assert main(["export", str(runs[case]), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(runs[case]) in err and why in err and "--force" in err and "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == []
    assert main(["export", str(runs[case]), "--out", str(out), "--force"]) == 0
    assert "warning: exported with --force" in capsys.readouterr().err
    (line,) = _warning(out)
    assert why in line and "exported with --force" in line
    lines = out.read_text().splitlines()
    assert lines[0] == "CCSDS_OEM_VERS = 2.0" and lines[1] == line  # a header comment, where KVN allows one
    oem = pytest.importorskip("oem")
    assert len(list(oem.OrbitEphemerisMessage.open(str(out)).segments[0].states)) > 0  # still a valid OEM


@pytest.mark.parametrize("summary", ["x", {"verdict": "x"}, [1, 2]])
def test_a_manifest_whose_summary_or_verdict_is_not_a_table_is_refused_unless_force(runs, tmp_path, summary, capsys):
    import json
    import shutil

    d = tmp_path / "edited"
    shutil.copytree(runs["finished"], d)
    manifest = json.loads((d / "manifest.json").read_text())
    (d / "manifest.json").write_text(json.dumps({**manifest, "summary": summary}))
    assert main(["export", str(d), "--out", str(tmp_path / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert "summary or verdict is not a table" in err and "--force" in err and "Traceback" not in err
    assert main(["export", str(d), "--out", str(tmp_path / "x.oem"), "--force"]) == 0


def test_a_running_then_killed_run_is_refused_unless_force(tmp_path, capsys):
    run = tmp_path / "r"
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(run), "--quiet",
                             "--rows-per-part", "1"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and proc.poll() is None:
            if (run / "estimates-parts").is_dir() and len(list((run / "estimates-parts").glob("part-*"))) >= 2:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the run ended before it could be stopped"
        proc.send_signal(signal.SIGSTOP)
        assert main(["export", str(run), "--out", str(tmp_path / "a.oem")]) == 2
        assert f"it is still running (process {proc.pid} " in capsys.readouterr().err
    finally:
        proc.kill()
        proc.wait(timeout=60)
    assert read_manifest(run)["status"] == "running"  # as a killed run leaves it
    assert main(["export", str(run), "--out", str(tmp_path / "a.oem")]) == 2
    err = capsys.readouterr().err
    assert "was interrupted or killed before it finished" in err and "--force" in err
    assert not (tmp_path / "a.oem").exists()
    assert main(["export", str(run), "--out", str(tmp_path / "a.oem"), "--force"]) == 0
    assert "interrupted or killed" in _warning(tmp_path / "a.oem")[0]


def test_a_full_disk_during_export_leaves_no_file_and_the_next_export_is_not_blocked(runs, small_disk, capsys):
    out = small_disk.path / "x.oem"
    small_disk.fill(0)
    assert main(["export", str(runs["finished"]), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: cannot write the oem file (No space left on device)" in err and "Traceback" not in err
    assert small_disk.files() == []  # neither the file nor a temporary one
    small_disk.free_up()
    assert main(["export", str(runs["finished"]), "--out", str(out)]) == 0  # no --overwrite needed
    assert out.read_text().startswith("CCSDS_OEM_VERS = 2.0") and _warning(out) == []


def test_a_run_that_fails_on_a_full_disk_prints_only_results_that_exist(small_disk, tmp_path):
    out = small_disk.path / "r"
    small_disk.fill(40 * 1024)  # room for the first files of the run, not for all of them
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), *SMALL_SET],
                          capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert proc.returncode == 3, proc.stderr
    assert ": failed (" in proc.stdout and "No space left on device" in proc.stdout
    assert "custody: kept" not in proc.stdout and "verdict: none" in proc.stdout
    (line,) = [x for x in proc.stdout.splitlines() if x.startswith("  results:")]
    named = re.findall(r"(\S+\.(?:parquet|json))", line)
    assert named and all(Path(p).exists() or "*" in p for p in named), line
    assert [f for f in small_disk.files() if f.stat().st_size == 0 or ".tmp" in f.name] == []
