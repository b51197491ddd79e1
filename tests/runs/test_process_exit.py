"""The command line ends a finished run's process without interpreter teardown
(cistrack.cli.process_exit), and that shortcut loses nothing: output flushed, results complete, exit
handlers run, exit status kept; the ordinary exit where the shortcut is not allowed."""
from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pyarrow.parquet as pq

SMALL = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
         "--set", "iod.n_particles=300"]


def _console(tmp_path, argv: list[str], prelude: str = "", env_extra: dict | None = None):
    """Run cistrack.cli.main.console_main (which the installed command calls) in a child process."""
    code = textwrap.dedent(prelude) + textwrap.dedent(f"""
        import sys
        from cistrack.cli.main import console_main
        sys.argv = ["cistrack", *{argv!r}]
        console_main()
        """)
    import os
    env = dict(os.environ, **(env_extra or {}))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, env=env,
                          timeout=600)


def test_a_run_ends_with_its_output_flushed_and_its_results_complete(tmp_path):
    out = tmp_path / "r"
    proc = _console(tmp_path, ["run", "quick", "--out", str(out), *SMALL])
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.rstrip().splitlines()
    last = max(i for i, line in enumerate(lines) if line.startswith("  results: "))
    assert all(line.startswith("    ") for line in lines[last + 1:])  # the results (wrapped) are printed last
    steps = pq.read_table(out / "steps.parquet")
    assert steps.num_rows > 1
    assert json.loads((out / "manifest.json").read_text())["status"] == "finished"


def test_exit_handlers_registered_during_the_run_still_run(tmp_path):
    flag = tmp_path / "handler-ran"
    prelude = f"""
        import atexit, pathlib
        atexit.register(lambda: pathlib.Path({str(flag)!r}).write_text("yes"))
        """
    proc = _console(tmp_path, ["run", "quick", "--quiet", "--out", str(tmp_path / "r"), *SMALL], prelude)
    assert proc.returncode == 0, proc.stderr
    assert flag.read_text() == "yes"


def test_the_exit_status_of_a_refused_command_is_kept(tmp_path):
    proc = _console(tmp_path, ["run", "no-such-scenario", "--quiet"])
    assert proc.returncode == 2
    assert "no-such-scenario" in proc.stderr


def test_full_exit_can_be_asked_for_and_gives_the_same_results(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert _console(tmp_path, ["run", "quick", "--quiet", "--out", str(a), *SMALL]).returncode == 0
    proc = _console(tmp_path, ["run", "quick", "--quiet", "--out", str(b), *SMALL], env_extra={"CISTRACK_FULL_EXIT": "1"})
    assert proc.returncode == 0, proc.stderr
    ta, tb = pq.read_table(a / "steps.parquet").to_pydict(), pq.read_table(b / "steps.parquet").to_pydict()
    assert {k: v for k, v in ta.items() if not k.startswith("time_")} == \
        {k: v for k, v in tb.items() if not k.startswith("time_")}


def test_a_command_that_did_not_allow_it_exits_the_ordinary_way(tmp_path):
    # an object whose finaliser prints at interpreter teardown: seen only when teardown happens
    prelude = """
        class _Tell:
            def __del__(self):
                print("teardown ran", flush=True)
        _keep = _Tell()
        """
    assert "teardown ran" in _console(tmp_path, ["scenarios"], prelude).stdout
    ran = _console(tmp_path, ["run", "quick", "--quiet", "--out", str(tmp_path / "r"), *SMALL], prelude)
    assert ran.returncode == 0 and "teardown ran" not in ran.stdout
