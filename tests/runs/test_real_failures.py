"""Real failures, not simulated ones (issue 17, item 3): the kernel's own ENOSPC from /dev/full
while a run writes its results, and directories the run may not write (as an unprivileged user:
these tests run as root, for whom permission bits do not bite, so the CLI is started as ``nobody``
through ``setpriv``). Each ends with a clear message, the completed steps readable and a manifest
that says what happened."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cistrack.plugin.hookspecs import hookimpl
from cistrack.results.store import read_manifest, read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

FULL = Path("/dev/full")
needs_dev_full = pytest.mark.skipif(not FULL.exists(), reason="no /dev/full on this system")
SMALL = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
         "--set", "iod.n_particles=300"]


def _small():
    return load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2},
                                                  "iod": {"n_particles": 300}})


class DiskFullsAtPart:
    """Points the temporary file of part ``k`` at /dev/full once the results writer has started
    (``trylast``: after it cleared old parts), so that writing that part meets the disk-full error
    of the kernel itself."""

    def __init__(self, directory: Path, k: int):
        self.link = directory / "steps" / f"part-{k:09d}.tmp"

    @hookimpl(trylast=True)
    def cistrack_run_started(self, run):
        self.link.symlink_to(FULL)


@needs_dev_full
def test_a_full_disk_during_the_run_ends_failed_with_the_written_steps_merged(tmp_path):
    out = tmp_path / "r"
    res = run_scenario(_small(), seed=1, output_dir=out, rows_per_part=1, observers=[DiskFullsAtPart(out, 3)])
    assert res.summary.status == "failed" and "No space left on device" in res.summary.failure
    man = read_manifest(out)
    assert man["status"] == "failed" and "No space left on device" in man["summary"]["failure"]
    steps = read_steps(out)
    assert steps.column("step").to_pylist() == [0, 1, 2]  # every step before the full disk, merged
    assert FULL.is_char_device()  # /dev/full itself untouched (the link was replaced, not followed)


@needs_dev_full
def test_a_full_disk_at_the_merge_keeps_the_parts_and_the_cli_says_failed(tmp_path):
    out = tmp_path / "r"
    out.mkdir()
    (out / "manifest.json").write_text('{"run_id": "earlier", "versions": {"cistrack": "0.2.0"}}')  # an earlier
    # results directory, which --out may replace
    (out / "steps.parquet.tmp").symlink_to(FULL)
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), *SMALL],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 3, proc.stderr
    assert "failed" in proc.stdout and "No space left on device" in proc.stdout
    assert "Traceback" not in proc.stdout + proc.stderr
    man = read_manifest(out)
    assert man["status"] == "failed" and "No space left on device" in man["merge_failure"]
    assert not (out / "steps.parquet").exists() and read_steps(out).num_rows == man["summary"]["n_steps"] > 3



def _as_nobody(args, cwd, tmp_path):
    if os.geteuid() != 0:
        pytest.skip("needs root to start the command as the unprivileged user nobody")
    if shutil.which("setpriv") is None:
        pytest.skip("setpriv (util-linux) is not installed: no way to drop root's permission override")
    env = dict(os.environ, CISTRACK_KERNEL_DIR=str(tmp_path / "kernels"), HOME=str(tmp_path),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    for d in ("kernels", "numba"):
        (tmp_path / d).mkdir(exist_ok=True)
        os.chown(tmp_path / d, 65534, 65534)
        os.chmod(tmp_path / d, 0o700)
    os.chmod(tmp_path, 0o755)
    nobody = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", sys.executable]
    probe = subprocess.run([*nobody, "-c", "import cistrack.cli.main"], capture_output=True, text=True, cwd=tmp_path,
                           env=env, timeout=120)
    if probe.returncode != 0:  # e.g. a checkout or venv inside a root-only 0700 folder (mktemp -d)
        pytest.skip("the unprivileged user nobody cannot import cistrack from this checkout: "
                    + (probe.stderr.strip().splitlines() or ["no message"])[-1])
    return subprocess.run([*nobody, "-m", "cistrack.cli", *args], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=600)


def _read_only_dir(path: Path) -> Path:
    path.mkdir()
    os.chown(path, 65534, 65534)
    path.chmod(0o555)
    return path


def test_a_read_only_output_directory_is_refused_before_computing(open_tmp):
    ro = _read_only_dir(open_tmp / "ro")
    proc = _as_nobody(["run", "quick", "--out", str(ro / "r"), *SMALL], open_tmp, open_tmp)
    assert proc.returncode == 2, proc.stderr
    assert "--out" in proc.stderr and "cannot write there" in proc.stderr and "Permission denied" in proc.stderr
    assert "Traceback" not in proc.stderr and list(ro.iterdir()) == []


def test_an_output_directory_nobody_may_search_is_refused_without_a_traceback(open_tmp):
    closed = open_tmp / "closed"
    closed.mkdir(mode=0o700)  # root's; nobody may not look inside
    proc = _as_nobody(["run", "quick", "--out", str(closed / "r"), *SMALL], open_tmp, open_tmp)
    assert proc.returncode == 2, proc.stderr
    assert "--out" in proc.stderr and "Permission denied" in proc.stderr and "Traceback" not in proc.stderr


def test_a_read_only_working_directory_is_refused_before_computing(open_tmp):
    ro = _read_only_dir(open_tmp / "ro")
    proc = _as_nobody(["run", "quick", *SMALL], ro, open_tmp)
    assert proc.returncode == 2, proc.stderr
    assert "results directory" in proc.stderr and "Permission denied" in proc.stderr
    assert "Traceback" not in proc.stderr and list(ro.iterdir()) == []
