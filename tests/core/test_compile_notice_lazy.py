"""A first call of a cached numba function that must compile says so (issue 15: on a fresh
install the mixture-density kernels compiled silently for tens of seconds after the IOD)."""
from __future__ import annotations

import subprocess
import sys

_PROBE = ("import logging, numpy as np\n"
          "logging.basicConfig(level=logging.INFO, format='%(name)s: %(message)s')\n"
          "from cistrack.model.mixture_density import _row_logsumexp\n"
          "out = np.empty(2)\n"
          "_row_logsumexp(0, 2, np.zeros((2, 3)), out)\n"
          "_row_logsumexp(0, 2, np.zeros((2, 3)), out)\n"
          "assert abs(out[0] - np.log(3.0)) < 1e-15\n")


def _stderr(cache_dir) -> str:
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    out = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stderr


def test_the_first_call_without_a_cache_says_it_compiles_and_the_next_process_loads_silently(tmp_path):
    first = _stderr(tmp_path)
    assert first.count("cistrack.lazy: compiling cistrack.model.mixture_density._row_logsumexp with numba") == 1
    assert "compiling" not in _stderr(tmp_path)
