"""process_timeline gives numba's import and set-up rows of their own."""
from __future__ import annotations

import os
import subprocess
import sys

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks", "process_timeline.py")


def test_the_timeline_of_a_run_names_numbas_import_and_target_context(tmp_path):
    done = subprocess.run([sys.executable, SCRIPT, "run", "quick", "--seed", "1", "--quiet", "--out", str(tmp_path / "run")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    stages = [line[:50].strip() for line in done.stderr.splitlines()]
    assert "import numba" in stages
    assert "numba target context (registries, scipy.linalg)" in stages
    assert stages.index("import numba") < stages.index("truth (dense kernel load + integration)")
