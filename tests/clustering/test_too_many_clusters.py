"""A third-party clusterer that returns more clusters than the PGM asked for (probe N5).

The contract (docs/plugins.md): given ``n_components = M`` a clusterer returns at most M clusters,
unless it declares ``chooses_n_components``. One returning 50 for 4 had been accepted: every
cluster fell under ``min_cluster_size`` and the PGM ran the whole run with one component, exit 0.
The run now fails naming the clusterer, what it returned and what was asked. A real plugin
distribution on PYTHONPATH, the real CLI in a subprocess."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from plugin_site import plugin_site  # tests/ is on sys.path

TOO_MANY = '''
import numpy as np

from cistrack.api import hookimpl
from cistrack.interfaces import Clusterer
from cistrack.interfaces.component import check_int


class TooMany(Clusterer):
    """Returns 50 clusters whatever it is asked for.

    Parameters
    ----------
    n_components : int
        Clusters asked for.
    """

    def __init__(self, n_components: int = 4):
        self.n_components = check_int(self, "n_components", n_components, minimum=1)

    def cluster(self, x, rng):
        return np.arange(x.shape[0]) % 50


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "too-many", TooMany)
'''


def _cli(site: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=600)


def test_a_clusterer_returning_more_clusters_than_asked_fails_the_run_by_name(tmp_path):
    site = plugin_site(tmp_path / "site", "cistrack-too-many", "0.1", {"cistrack_too_many": TOO_MANY})
    done = _cli(site, tmp_path, "run", "quick", "--set", "filter.clusterer=too-many", "--out", str(tmp_path / "run"))
    assert done.returncode != 0, done.stdout
    assert "clusterer 'too-many'" in done.stderr
    assert "returned 50 clusters where n_components = 4 asked for at most 4" in done.stderr
