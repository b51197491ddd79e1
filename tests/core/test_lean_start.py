"""Listing components must not load the heavy libraries the components use (issue 14).

`cistrack --help` and `cistrack plugins` run in a fraction of a second only if importing
cistrack and filling the registry leaves scikit-learn, numba, rerun, matplotlib, filterpy,
astropy, Dask, pyarrow and urllib.request unloaded; they load when a component is built or used. Each check runs in a
fresh interpreter, since this test process has long since imported everything.
"""
from __future__ import annotations

import functools
import json
import subprocess
import sys

import pytest

HEAVY = ("sklearn", "numba", "rerun", "matplotlib", "filterpy", "astropy", "dask",
         "pyarrow",          # ~35 ms: only writing or reading results needs it
         "urllib.request",   # ~12 ms: xml.sax.saxutils imports it; the ADES XML writer escapes itself
         "numpy.random")     # ~20 ms: numpy loads it on first use


@functools.lru_cache(maxsize=None)  # one fresh interpreter per probe, shared by the parametrised cases
def _loaded_after(code: str) -> list[str]:
    probe = (f"import sys\n{code}\n"
             f"print(__import__('json').dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
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
    # numba: the probe can see a load; matplotlib: the run draws its residuals.svg
    assert json.loads(out.stdout.strip().splitlines()[-1]) == ["matplotlib", "numba"]
