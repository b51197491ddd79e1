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
