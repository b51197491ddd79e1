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
