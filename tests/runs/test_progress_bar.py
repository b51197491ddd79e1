"""The run's progress bar on stderr: on a terminal it redraws often; into a file or a CI log, where
every redraw is kept, only at its interval and at the end, with the final state shown."""
from __future__ import annotations

import subprocess
import sys


def test_into_a_file_the_bar_redraws_at_its_interval_not_at_every_step(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(tmp_path / "run"),
                           "--set", "filter.n_particles=300", "--set", "iod.n_particles=300"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    draws = [line for line in proc.stderr.replace("\r", "\n").split("\n") if "step" in line and "%|" in line]
    total = int(draws[-1].split("|")[2].split("/")[1].split()[0])
    assert total > 10 and len(draws) <= 4
    assert f"{total}/{total}" in draws[-1] and "t=" in draws[-1] and "H=" in draws[-1]


def test_a_stage_line_said_while_the_bar_is_shown_starts_a_line_of_its_own(monkeypatch):
    import io

    from cistrack.runs.progress import ProgressBar, stage_log

    err = io.StringIO()  # not a terminal: the bar's draws are kept, with no newline after them
    monkeypatch.setattr(sys, "stderr", err)
    bar = ProgressBar("run-x", 10)
    bar.bar.update(1)
    bar.bar.refresh()
    stage_log()("maneuver detected at 2.000 d")
    bar.bar.close()
    lines = err.getvalue().replace("\r", "\n").split("\n")
    assert "  maneuver detected at 2.000 d" in lines


def test_the_bar_of_a_run_with_a_long_name_stays_within_120_columns(monkeypatch):
    import io

    from cistrack.runs.progress import ProgressBar

    err = io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    bar = ProgressBar("example-1-burn__pgm__uniform-range-velocity-bound__seed123456__with-a-long-tail", 40)
    bar.bar.set_postfix_str("t=3.62 d H=-21.4 custody LOST")
    bar.bar.update(7)
    bar.bar.close()
    draws = [d for d in err.getvalue().replace("\r", "\n").split("\n") if d]
    assert draws and max(len(d) for d in draws) <= 120


def test_outside_ipython_the_bar_is_tqdms_text_bar_and_asyncio_is_not_imported():
    code = ("import sys; from cistrack.runs.progress import ProgressBar; import tqdm.std; "
            "b = ProgressBar('r', 3); b.bar.close(); "
            "print(type(b.bar) is tqdm.std.tqdm, 'asyncio' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.stdout.split() == ["True", "False"], proc.stderr[-2000:]


def test_under_ipython_the_bar_is_tqdm_autos_choice(monkeypatch):
    import types

    import tqdm.auto

    from cistrack.runs.progress import bar_class

    monkeypatch.setitem(sys.modules, "IPython", types.ModuleType("IPython"))
    assert bar_class() is tqdm.auto.tqdm
