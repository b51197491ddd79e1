"""Listing components must not load the heavy libraries the components use (issue 14).

`cistrack --help` and `cistrack plugins` run in a fraction of a second only if importing
cistrack and filling the registry leaves scikit-learn, numba, rerun, matplotlib, filterpy,
astropy, ERFA, Dask, pyarrow and urllib.request unloaded; they load when a component is built or
used. A run with its results and residual figure loads neither matplotlib nor pandas (issue 51).
Each check runs in a fresh interpreter, since this test process has long since imported everything.
"""
from __future__ import annotations

import functools
import json
import os
import subprocess
import sys

import pytest

HEAVY = ("sklearn", "numba", "rerun", "matplotlib", "filterpy", "astropy", "dask",
         "pyarrow",          # ~35 ms: only writing or reading results needs it
         "urllib.request",   # ~12 ms: xml.sax.saxutils imports it; the ADES XML writer escapes itself
         "numpy.random",     # ~20 ms: numpy loads it on first use
         "erfa",             # ~15 ms: the real sky's, loaded on its first use (issue 51)
         "difflib")          # ~5 ms: only an unknown name's suggestion needs it (issue 51)


@functools.lru_cache(maxsize=None)  # one fresh interpreter per probe, shared by the parametrised cases
def _loaded_after(code: str, modules: tuple[str, ...] = HEAVY) -> list[str]:
    probe = (f"import sys\n{code}\n"
             f"print(__import__('json').dumps([m for m in {modules!r} if m in sys.modules]))")
    # built-in components only: a third-party test plugin another test installs meanwhile may load anything
    env = {**os.environ, "CISTRACK_DISABLE_PLUGIN_AUTOLOAD": "1"}
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_cistrack_loads_no_heavy_library():
    assert _loaded_after("import cistrack") == []


_REGISTRY = ("from cistrack.plugin.registry import load_registry\n"
             "reg = load_registry()\n"
             "assert not reg.failures, reg.failures\n"
             "assert 'pgm' in reg.names('filter') and 'rerun' in reg.names('recorder')")
_CLI = ("import contextlib, io\n"
        "from cistrack.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['plugins']) == 0\n")
@pytest.mark.parametrize("library", HEAVY)
@pytest.mark.parametrize("code", [_REGISTRY, _CLI], ids=["registry", "cli-plugins"])
def test_listing_components_does_not_load(library, code):
    assert library not in _loaded_after(code)


_KMEANS = ("import numpy as np\n"
           "from cistrack.plugin.registry import load_registry\n"
           "c = load_registry().create('clustering', 'kmeans', n_components=2{})\n"
           "c.cluster(np.random.default_rng(1).normal(size=(40, 6)), np.random.default_rng(2))")


def test_scikit_learn_loads_when_the_sklearn_kmeans_engine_clusters():
    """The probe itself can fail: the sklearn engine does load scikit-learn."""
    assert "sklearn" in _loaded_after(_KMEANS.format(", engine='sklearn'"))


def test_the_default_kmeans_clusters_without_loading_scikit_learn():
    """The PGM's default clusterer runs in numpy: importing sklearn.cluster costs ~1.3 s of CPU."""
    assert "sklearn" not in _loaded_after(_KMEANS.format(""))


def test_rerun_loads_when_the_recorder_records(tmp_path):
    code = ("from cistrack.plugin.registry import load_registry\n"
            f"c = load_registry().create('recorder', 'rerun', path={str(tmp_path / 'r.rrd')!r})\n"
            "import cistrack.plugins.recorders.rerun_recorder as m\n"
            "m.rr.RecordingStream")
    assert "rerun" in _loaded_after(code)


def test_version_option_prints_the_installed_version():
    import cistrack

    out = subprocess.run([sys.executable, "-m", "cistrack.cli", "--version"], capture_output=True, text=True)
    assert out.returncode == 0
    assert out.stdout.strip() == f"cistrack {cistrack.__version__}"



def test_a_pgm_run_loads_neither_scikit_learn_nor_filterpy_nor_scipy_stats(tmp_path):
    """Issue 15: a default PGM run (k-means, iterated update, results written) paid ~2.7 s of CPU
    for importing sklearn.cluster, filterpy.kalman and scipy.stats; none of them is needed."""
    probe = ("import json, sys\n"
             "from cistrack.cli.main import main\n"
             f"assert main(['run', 'quick', '--quiet', '--out', {str(tmp_path / 'run')!r}]) == 0\n"
             "print(json.dumps([m for m in ('sklearn', 'filterpy', 'scipy.stats', 'matplotlib', 'numba')"
             " if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    # numba: the probe can see a load
    assert json.loads(out.stdout.strip().splitlines()[-1]) == ["numba"]


# Issue 51: what a command-line run with results and its residual figure does not need
RUN_LAZY = ("matplotlib",        # ~0.8 s to import: residuals.svg is written as text
            "pandas",            # ~0.35 s: pyarrow's to_numpy and read_table (pyarrow.dataset) import it
            "pyarrow.dataset",   # pq.read_table's; a plain file reads through ParquetFile
            "pyarrow.compute",
            "erfa")              # the real sky's (core/astro/observer.py, sky.py): not a CR3BP run's


@functools.lru_cache(maxsize=None)
def _loaded_by_a_run(out: str) -> tuple[list[str], bool]:
    probe = ("import json, os, sys\n"
             "from cistrack.cli.main import main\n"
             f"assert main(['run', 'quick', '--set', 'duration_days=1.5', '--quiet', '--out', {out!r}]) == 0\n"
             f"print(json.dumps([[m for m in {RUN_LAZY!r} if m in sys.modules],"
             f" os.path.exists(os.path.join({out!r}, 'residuals.svg'))]))")
    res = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    loaded, figure = json.loads(res.stdout.strip().splitlines()[-1])
    return loaded, figure


@pytest.mark.parametrize("library", RUN_LAZY)
def test_a_run_that_writes_its_results_and_residual_figure_does_not_load(library, tmp_path_factory):
    loaded, figure = _loaded_by_a_run(str(tmp_path_factory.getbasetemp() / "lean-run"))
    assert figure  # the figure was drawn: the probe covers its code
    assert library not in loaded


def test_importing_the_run_pipeline_loads_no_scipy():
    """scipy.special (~0.1-0.3 s with scipy's array-API layer) loads when a metric first needs it:
    ``import cistrack.runs.pipeline`` (the Python API's run) does not pay for it up front."""
    assert _loaded_after("import cistrack.runs.pipeline, cistrack.cli.main", ("scipy", "scipy.special")) == []
