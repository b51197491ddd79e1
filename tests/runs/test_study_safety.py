"""A study never reports success over lost results, never writes where it should not, and never
leaves workers behind (issue 27, item 2): real `cistrack study run` processes, a real full disk
(a small tmpfs), a real `kill -9`, two real study processes on one directory."""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from study_files import write_study

from cistrack.cli.main import main
from cistrack.results.store import read_manifest
from cistrack.studies.resume import run_state

needs_proc = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")


def _study(tmp_path: Path, name: str = "safe", seeds: str = "[1, 2, 3]", days: float = 1.4) -> Path:
    return write_study(tmp_path, name, seeds, days)


def _cli(*args: str, cwd: Path, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=600, **kw)


def _start(*args: str, cwd: Path, log: Path | None = None) -> subprocess.Popen:
    """Start the command; its output to pipes, or both to the file ``log`` (a pipe would stay open
    as long as any process that inherited it lives)."""
    out = open(log, "w") if log is not None else subprocess.PIPE
    try:
        return subprocess.Popen([sys.executable, "-m", "cistrack.cli", *args], stdout=out,
                                stderr=subprocess.STDOUT if log is not None else subprocess.PIPE, text=True, cwd=cwd)
    finally:
        if log is not None:
            out.close()


def _wait_for_a_run(proc: subprocess.Popen, out: Path) -> None:
    """Wait until the study process has started writing a run (it holds its directory then)."""
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None:
        if list((out / "runs").glob("*/manifest.json")) if (out / "runs").is_dir() else []:
            return
        time.sleep(0.05)
    raise AssertionError(f"the study never started a run (rc {proc.poll()})")


def _statuses(out: Path) -> list[str]:
    return [read_manifest(d)["status"] for d in sorted((out / "runs").iterdir())]


# --out: the same rule as `cistrack run --out` -----------------------------------------------------------

@pytest.mark.parametrize("case", ["file", "run-dir", "other-study", "foreign-dir"])
def test_study_out_is_refused_unless_new_empty_or_the_same_study(case, tmp_path, capsys):
    study = _study(tmp_path)
    out = {"file": tmp_path / "f.txt", "run-dir": tmp_path / "run", "other-study": tmp_path / "other",
           "foreign-dir": tmp_path / "photos"}[case]
    if case == "file":
        out.write_text("not a directory\n")
    elif case == "run-dir":
        out.mkdir()
        (out / "manifest.json").write_text("{}")
    elif case == "other-study":
        out.mkdir()
        (out / "study.json").write_text(json.dumps({"name": "another", "source": "another.toml", "run_seeds": [1]}))
    elif case == "foreign-dir":
        out.mkdir()
        (out / "holiday.jpg").write_bytes(b"\xff\xd8")
    before = sorted(p.name for p in out.iterdir()) if out.is_dir() else None
    assert main(["study", "run", str(study), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}" in err and "new or empty directory" in err and "Traceback" not in err
    assert {"file": "not a directory", "run-dir": "single run", "other-study": "another study ('another')",
            "foreign-dir": "holds no study.json"}[case] in err
    if before is not None:
        assert sorted(p.name for p in out.iterdir()) == before  # nothing written there


def test_an_empty_directory_and_the_same_study_again_are_accepted(tmp_path, capsys):
    study = _study(tmp_path, seeds="[1]")
    out = tmp_path / "empty"
    out.mkdir()
    assert main(["study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet"]) == 0
    assert main(["study", "run", str(study), "--out", str(out), "--workers", "1"]) == 0
    assert "0 runs completed, 1 already done, 0 failed" in capsys.readouterr().out



def _as_nobody(open_tmp: Path, *args: str) -> subprocess.CompletedProcess:
    """The command run as the unprivileged user ``nobody`` (root's permission override would hide
    a read-only place), from ``open_tmp``."""
    if os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("needs root and setpriv to start the command as the unprivileged user nobody")
    for d in ("kernels", "numba", "w"):
        (open_tmp / d).mkdir(exist_ok=True)
        os.chown(open_tmp / d, 65534, 65534)
    env = dict(os.environ, CISTRACK_KERNEL_DIR=str(open_tmp / "kernels"), HOME=str(open_tmp),
               NUMBA_CACHE_DIR=str(open_tmp / "numba"))
    proc = subprocess.run(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", sys.executable, "-m",
                           "cistrack.cli", *args], capture_output=True, text=True, cwd=open_tmp, env=env, timeout=600)
    if "No module named" in proc.stderr:
        pytest.skip("the user nobody cannot import cistrack from this checkout")
    return proc


def test_the_root_of_the_file_system_is_refused_as_out(open_tmp):
    study = _study(open_tmp, seeds="[1]")  # as nobody: a failure of the check cannot write into /
    proc = _as_nobody(open_tmp, "study", "run", str(study), "--out", "/", "--quiet")
    assert proc.returncode == 2, proc.stderr
    assert "--out /: the root of the file system" in proc.stderr and "new or empty directory" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("option", ["--out", "--rerun"])
def test_a_read_only_place_for_out_or_rerun_is_refused_naming_the_option(option, open_tmp):
    ro = open_tmp / "ro"
    ro.mkdir()
    os.chown(ro, 65534, 65534)
    ro.chmod(0o555)
    study = _study(open_tmp, seeds="[1]")
    out = ro / "s" if option == "--out" else open_tmp / "w" / "s"
    args = ["study", "run", str(study), "--out", str(out), "--quiet"] + (["--rerun", str(ro / "rec")]
                                                                         if option == "--rerun" else [])
    proc = _as_nobody(open_tmp, *args)
    assert proc.returncode == 2, proc.stderr
    assert f"{option} {ro}" in proc.stderr and "cannot write there" in proc.stderr
    assert "Permission denied" in proc.stderr and "Traceback" not in proc.stderr
    assert list(ro.iterdir()) == []


# one study process per directory; none survives its parent -----------------------------------------

def test_a_second_study_run_on_the_same_out_is_refused_while_the_first_runs(tmp_path):
    study = _study(tmp_path, seeds="[1, 2, 3]")
    out = tmp_path / "s"
    first = _start("study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet", cwd=tmp_path)
    try:
        _wait_for_a_run(first, out)
        first.send_signal(signal.SIGSTOP)  # it holds the directory for as long as the second one needs
        try:
            second = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet", cwd=tmp_path)
        finally:
            first.send_signal(signal.SIGCONT)
        _, err = first.communicate(timeout=600)
    finally:
        if first.poll() is None:
            first.kill()
    assert second.returncode == 2, second.stderr
    assert f"--out {out}" in second.stderr and "another 'cistrack study run'" in second.stderr
    assert f"process {first.pid} " in second.stderr and "Traceback" not in second.stderr
    assert first.returncode == 0, err
    assert _statuses(out) == ["finished"] * 3


def _children(pid: int) -> list[int]:
    kids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == pid:
                kids.append(int(stat.parent.name))
        except (OSError, IndexError, ValueError):
            continue
    return kids


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")  # a zombie has ended (nobody has read its status yet)


@needs_proc
def test_kill_9_of_a_study_leaves_no_worker_and_no_lock_and_the_next_run_completes_it(tmp_path):
    study = _study(tmp_path, seeds="[1, 2, 3]")
    out = tmp_path / "s"
    proc = _start("study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet", cwd=tmp_path,
                  log=tmp_path / "study.log")
    kids: list[int] = []
    try:
        _wait_for_a_run(proc, out)
        kids = _children(proc.pid)
        proc.kill()  # SIGKILL: no handler runs in the study process
        proc.wait(timeout=60)
        assert kids, "the study process had no worker process"
        deadline = time.monotonic() + 120  # a limit on waiting, not a timing requirement
        while time.monotonic() < deadline and any(_alive(k) for k in kids):
            time.sleep(0.1)
        assert [k for k in kids if _alive(k)] == [], "a worker outlived the killed study process"
    finally:
        if proc.poll() is None:
            proc.kill()
        for k in kids:  # whatever the outcome, no process of this test is left behind
            if _alive(k):
                os.kill(k, signal.SIGKILL)
    n_started = len(list((out / "runs").glob("*/manifest.json")))
    assert n_started < 3  # the orphan did not go on with the study
    again = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert _statuses(out) == ["finished"] * 3
    assert "0 failed" in again.stdout


# a full disk: never success over lost results, never a file that blocks the next attempt -------------

def test_a_full_disk_makes_the_study_fail_naming_every_lost_run_and_the_retry_completes(small_disk, tmp_path):
    study = _study(tmp_path, seeds="[1, 2, 3]")
    out = small_disk.path / "s"
    small_disk.fill(48 * 1024)  # room for the study record and about one run
    proc = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 3, proc.stderr
    assert "Traceback" not in proc.stderr
    runs = {d.name: run_state(str(d)) for d in sorted((out / "runs").iterdir())} if (out / "runs").is_dir() else {}
    ids = [f"quick__pgm__noisy-range__seed{s}" for s in (1, 2, 3)]
    lost = [r for r in ids if runs.get(r) != "done"]
    assert lost, "the disk was not full enough to lose a run"
    for r in ids:  # every lost run named with a reason, no finished run named
        assert (f"run {r} did not finish: " in proc.stderr) == (r in lost)
    assert f"{len(lost)} of 3 runs did not finish" in proc.stderr
    assert f"{3 - len(lost)} runs completed, 0 already done, {len(lost)} failed" in proc.stdout
    assert [f for f in small_disk.files() if f.stat().st_size == 0 and not f.name.startswith(".study")] == []
    assert [f for f in small_disk.files() if f.name.endswith(".tmp")] == []  # no temporary file left behind
    small_disk.free_up()
    again = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert f"{len(lost)} runs completed, {3 - len(lost)} already done, 0 failed" in again.stdout
    assert _statuses(out) == ["finished"] * 3


def test_a_disk_too_full_for_the_study_record_is_refused_and_leaves_nothing_to_block_a_retry(small_disk, tmp_path):
    study = _study(tmp_path, seeds="[1]")
    out = small_disk.path / "s"
    small_disk.fill(0)
    proc = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert f"--out {out}" in proc.stderr and "study.json" in proc.stderr and "No space left" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (out / "study.json").exists() and [f for f in small_disk.files() if f.stat().st_size == 0
                                                  and not f.name.startswith(".study")] == []
    small_disk.free_up()
    again = _cli("study", "run", str(study), "--out", str(out), "--workers", "1", "--quiet", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert _statuses(out) == ["finished"]


def _sigint_disposition() -> str:
    return "ignored" if signal.getsignal(signal.SIGINT) is signal.SIG_IGN else "handled"


def test_a_study_worker_leaves_ctrl_c_to_the_study_process():
    """A terminal's Ctrl-C reaches every process of the group: a worker that stopped its run on it
    was stopped again by the study's SIGTERM while writing its manifest, which stayed "running"."""
    from cistrack.studies.study import make_executor

    ex = make_executor(workers=1)
    try:
        assert ex.submit(_sigint_disposition).result(timeout=120) == "ignored"
    finally:
        ex.shutdown()


@needs_proc
def test_ctrl_c_ends_a_study_at_once_with_no_worker_left_and_the_next_run_completes_it(tmp_path):
    study = _study(tmp_path, seeds="[1, 2, 3, 4]", days=6.0)
    out = tmp_path / "s"
    with open(tmp_path / "study.log", "w") as log:  # Ctrl-C reaches the whole process group, workers included
        proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "study", "run", str(study), "--out", str(out),
                                 "--workers", "2", "--quiet"], stdout=log, stderr=subprocess.STDOUT, cwd=tmp_path,
                                start_new_session=True,  # SIGINT as a terminal leaves it, even under '&'
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    kids: list[int] = []
    try:
        _wait_for_a_run(proc, out)
        kids = _children(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)
        assert proc.wait(timeout=120) == 130  # a limit on waiting (a hang fails), not a timing requirement
        deadline = time.monotonic() + 60  # multiprocessing's resource tracker ends just after the study
        while time.monotonic() < deadline and any(_alive(k) for k in kids):
            time.sleep(0.1)
        assert [k for k in kids if _alive(k)] == [], "a worker outlived the interrupted study"
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        for k in kids:
            if _alive(k):
                os.kill(k, signal.SIGKILL)
    assert "interrupted (SIGINT); finished runs are kept" in (tmp_path / "study.log").read_text()
    assert "running" not in _statuses(out)  # a worker that took the Ctrl-C itself was stopped mid-write
    again = _cli("study", "run", str(study), "--out", str(out), "--workers", "2", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert _statuses(out) == ["finished"] * 4
