"""A Ctrl-C while a command first imports numba ends the command as interrupted (probe J1).

numba's C extension imports ``numba._devicearray`` itself: the handler's RunInterrupted raised
there had been printed as a traceback and turned into ``ImportError: numba._devicearray failed to
import`` (exit 1); and one noted but lost in a callback had let ``predict`` finish, exit 0, files
written. The Ctrl-C is sent from inside the process at the moment numba imports that module (an
audit hook), so the moment never depends on the machine's load."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from real_data_fit import fitted_example  # tests/ is on sys.path

from cistrack.cli.signals import install_signal_handlers, interrupts_prevail
from cistrack.errors import RunInterrupted
from cistrack.interrupts import clear

_PREDICT_WITH_A_CTRL_C = """
import signal, sys
def at_devicearray(event, args):
    if event == "import" and args and args[0] == "numba._devicearray":
        {action}
sys.addaudithook(at_devicearray)
from cistrack.cli.main import console_main
sys.argv = ["cistrack", *sys.argv[1:]]
console_main()
"""


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    return fitted_example(tmp_path_factory)


def _predict(fitted, tmp_path, action: str) -> subprocess.CompletedProcess:
    code = _PREDICT_WITH_A_CTRL_C.format(action=action)
    argv = [sys.executable, "-c", code, "predict", str(fitted), "--site", "568", "--start", "2026-03-07T00:00:00Z",
            "--stop", "2026-03-07T06:00:00Z", "--step", "60", "--quiet", "--out", str(tmp_path / "p")]
    return subprocess.run(argv, capture_output=True, text=True, env=dict(os.environ), timeout=300)


def test_a_ctrl_c_while_numbas_c_extension_imports_ends_predict_as_interrupted(fitted, tmp_path):
    proc = _predict(fitted, tmp_path, "signal.raise_signal(signal.SIGINT)")
    assert proc.returncode == 130
    assert proc.stderr.strip() == "cistrack: interrupted (SIGINT)"
    assert not list(tmp_path.glob("p.*"))


def test_a_ctrl_c_noted_but_lost_while_numba_imports_still_ends_predict_before_it_writes(fitted, tmp_path):
    lost = "from cistrack.errors import RunInterrupted; from cistrack.interrupts import note; note(RunInterrupted())"
    proc = _predict(fitted, tmp_path, lost)  # what the handler does in a callback that would drop the exception
    assert proc.returncode == 130
    assert proc.stderr.strip() == "cistrack: interrupted (SIGINT)"
    assert not list(tmp_path.glob("p.*"))


def test_any_exception_raised_after_a_ctrl_c_is_the_ctrl_c():
    import signal

    previous = install_signal_handlers()
    try:
        with pytest.raises(RunInterrupted), interrupts_prevail():
            try:
                signal.raise_signal(signal.SIGINT)
            except RunInterrupted as exc:  # what a C extension's import makes of it
                raise ImportError("numba._devicearray failed to import") from exc
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        clear()


def test_an_exception_without_a_ctrl_c_is_left_as_it_is():
    clear()
    with pytest.raises(ImportError, match="no such module"), interrupts_prevail():
        raise ImportError("no such module")
