"""What ``cistrack`` prints about a run and about plugins stays within 120 columns: a no-truth run's
measurement consistency, a diverged run's verdict, and a plugin-load warning (a pluggy validation
error, which breaks its own lines, becomes one wrapped message)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cistrack.cli.main import _print_outcome, main
from cistrack.evaluation.custody import Verdict
from cistrack.evaluation.run_summary import RunSummary
from plugin_site import plugin_site  # tests/ is on sys.path

MAX = 120
LONG_REASON = ("innovations blew up: NIS 1.34e+07 at this update and above 1e+06 on 3 consecutive updates "
               "(a consistent filter's NIS is about 2; the filter's predicted measurement is far from the data, "
               "so its belief no longer describes the object)")


def _too_wide(text: str) -> list[str]:
    return [line for line in text.splitlines() if len(line) > MAX]


def test_a_no_truth_runs_consistency_line_is_wrapped_and_kept_whole(tmp_path, capsys):
    assert main(["run", "real-data", "--out", str(tmp_path / "rd")]) == 0
    out = capsys.readouterr().out
    assert _too_wide(out) == []
    consistency = out[out.index("  measurement consistency: "):out.index("\n  ", out.index("nis)"))]
    assert "mean NIS" in consistency and consistency.count("\n") >= 1
    assert all(line.startswith(" " * 27) for line in consistency.splitlines()[1:])


def test_a_diverged_runs_verdict_is_wrapped_under_its_label(tmp_path, capsys):
    summary = RunSummary("x__ukf__seed1", 1, verdict=Verdict("diverged", LONG_REASON, 4, 1.2), has_truth=True)
    _print_outcome(summary, tmp_path, False, print)
    out = capsys.readouterr().out
    assert _too_wide(out) == []
    lines = out.splitlines()
    head = lines.index(next(line for line in lines if line.startswith("  verdict: diverged at step 4")))
    custody = lines.index(next(line for line in lines if line.startswith("  custody: ")))
    assert custody > head + 1 and all(line.startswith(" " * len("  verdict: ")) for line in lines[head + 1:custody])


BAD_HOOK = '''
from cistrack.api import hookimpl


@hookimpl
def cistrack_register(reg):       # the argument must be called 'registry'
    pass
'''


@pytest.fixture
def site(tmp_path: Path) -> Path:
    return plugin_site(tmp_path / "site", "cistrack-badhook", "1.0", {"cistrack_badhook_plugin": BAD_HOOK},
                       {"badhook": "cistrack_badhook_plugin"})


def _plugins_listing(site: Path, tmp_path: Path, stderr_on_terminal: bool) -> tuple[str, str]:
    """(stdout, stderr) of ``cistrack plugins --kind filter`` with the bad plugin on the path; stderr
    a pseudo-terminal or a pipe."""
    import pty

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    argv = [sys.executable, "-m", "cistrack.cli", "plugins", "--kind", "filter"]
    if not stderr_on_terminal:
        proc = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout, proc.stderr
    master, slave = pty.openpty()
    proc = subprocess.run(argv, stdout=subprocess.PIPE, stderr=slave, text=True, env=env, cwd=tmp_path, timeout=300)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the terminal's other end closed: all was read
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    assert proc.returncode == 0
    return proc.stdout, b"".join(chunks).decode().replace("\r\n", "\n")


def _own_warning(err: str) -> list[str]:
    """The lines of the bad plugin's warning in ``err``, from its first line to the next message:
    other tests install and remove broken plugin distributions in the shared environment meanwhile,
    and their warnings come too (seen twice in the parallel suite)."""
    lines = err.splitlines()
    first = next(i for i, line in enumerate(lines) if "plugin cistrack-badhook:" in line)
    rest = [i for i in range(first + 1, len(lines)) if lines[i].startswith("cistrack: ")]
    return lines[first:rest[0] if rest else len(lines)]


def test_a_plugin_load_warning_on_a_terminal_is_one_message_wrapped_within_120_columns(site, tmp_path):
    out, err = _plugins_listing(site, tmp_path, stderr_on_terminal=True)
    warning = _own_warning(err)
    assert warning[0].startswith("cistrack: warning: plugin cistrack-badhook: entry point 'badhook' failed: ")
    assert "PluginValidationError" in warning[0] and len(warning) > 1
    assert all(line.startswith(" " * len("cistrack: ")) for line in warning[1:]), err
    assert _too_wide(err) == [] and _too_wide(out) == []


def test_a_plugin_load_warning_to_a_pipe_is_one_line(site, tmp_path):
    _, err = _plugins_listing(site, tmp_path, stderr_on_terminal=False)
    (warning,) = _own_warning(err)
    assert warning.startswith("cistrack: warning: plugin cistrack-badhook: entry point 'badhook' failed: ")
