"""The CLI as the first stage of a shell pipe whose reader stops early."""
from __future__ import annotations

import subprocess
import sys


def test_a_reader_closing_the_pipe_early_ends_the_listing_quietly():
    code = ("import subprocess, sys; p = subprocess.Popen([sys.executable, '-m', 'cistrack.cli.main', "
            "'scenarios'], stdout=subprocess.PIPE, stderr=subprocess.PIPE); p.stdout.read(10); "
            "p.stdout.close(); err = p.stderr.read().decode(); rc = p.wait(); print(rc); print(err)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    rc, _, err = out.stdout.partition("\n")
    assert rc.strip() == "0", out.stdout
    assert "Traceback" not in err and "BrokenPipeError" not in err, err


def test_a_full_standard_output_is_named_in_the_error(tmp_path):
    """Output that cannot be written (here /dev/full: "No space left on device") is an error that
    says it was the standard output, not a bare system message."""
    import os

    import pytest

    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    with open("/dev/full", "w") as full:
        out = subprocess.run([sys.executable, "-m", "cistrack.cli.main", "scenarios"], stdout=full,
                             stderr=subprocess.PIPE, text=True, timeout=120)
    assert out.returncode == 2
    assert "cistrack: error: standard output: No space left on device" in out.stderr
    assert "Traceback" not in out.stderr


def _run_command(tmp_path) -> list[str]:
    """A short run of the built-in scenario ``quick`` into ``tmp_path/run`` (about a second)."""
    return [sys.executable, "-m", "cistrack.cli.main", "run", "quick", "--set", "duration_days=1.4",
            "--out", str(tmp_path / "run")]


def test_a_run_whose_log_reader_closes_early_finishes_and_writes_its_results(tmp_path):
    """``cistrack run ... 2>&1 | head -1``: the run had ended at once with exit status 0, having
    written nothing but its lock file."""
    code = ("import subprocess, sys; p = subprocess.Popen(sys.argv[1:], stdout=subprocess.PIPE, "
            "stderr=subprocess.STDOUT); p.stdout.read(10); p.stdout.close(); print(p.wait())")
    rc = subprocess.run([sys.executable, "-c", code, *_run_command(tmp_path)], capture_output=True, text=True,
                        timeout=300)
    assert rc.stdout.strip() == "0", rc.stdout + rc.stderr
    assert '"status": "finished"' in (tmp_path / "run" / "manifest.json").read_text()


def test_a_run_whose_standard_error_cannot_be_written_finishes_and_writes_its_results(tmp_path):
    """A script started with ``2>&-`` may hold a read-only file on descriptor 2: the run had ended
    with exit status 1, nothing written and nothing said."""
    readonly = tmp_path / "readonly.txt"
    readonly.write_text("")
    with open(readonly) as stderr:
        done = subprocess.run(_run_command(tmp_path), stdout=subprocess.PIPE, stderr=stderr, text=True, timeout=300)
    assert done.returncode == 0
    assert "finished" in done.stdout
    assert '"status": "finished"' in (tmp_path / "run" / "manifest.json").read_text()
