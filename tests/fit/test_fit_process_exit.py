"""`cistrack fit` ends its process without the interpreter's teardown once its results are written
(cistrack.cli.process_exit), and loses nothing by it: fit.json and the plots complete, exit status 0."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
FAST = ["--set", "iod.n_particles=1000", "--set", "filter.n_particles=1000"]


def test_a_fit_ends_without_interpreter_teardown_and_with_its_results_complete(tmp_path):
    out = tmp_path / "fit"
    argv = ["cistrack", "fit", str(DATA / "observations.psv"), "--out", str(out), "--quiet", *FAST]
    code = textwrap.dedent(f"""
        class _Tell:  # its finaliser prints only when the interpreter tears down
            def __del__(self):
                print("teardown ran", flush=True)
        _keep = _Tell()
        import sys
        from cistrack.cli.main import console_main
        sys.argv = {argv!r}
        console_main()
        """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                          env=dict(os.environ), timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "teardown ran" not in proc.stdout
    assert json.loads((out / "fit.json").read_text())["converged"]
    assert list(out.glob("residuals-*.png")) and list(out.glob("residuals-*.svg"))
