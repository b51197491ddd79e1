"""The step table's stage timings: the prediction's time includes forming the predicted belief,
which for the PGM is clustering its particles (the second half of its prediction)."""
from __future__ import annotations

import time

from cistrack.plugin.registry import load_registry
from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

PAUSE_S = 0.05


class _PausingKMeans(KMeansClusterer):
    """The real k-means, after a pause of PAUSE_S: a clusterer whose time is known to be at least that."""

    calls = 0

    def cluster(self, x, rng):
        type(self).calls += 1
        time.sleep(PAUSE_S)
        return super().cluster(x, rng)


def test_the_pgm_clustering_counts_in_the_prediction_time():
    reg = load_registry()
    reg.add("clustering", "pausing-kmeans", _PausingKMeans)
    scen = load_scenario("quick", reg, overrides={
        "duration_days": 1.4, "filter": {"n_particles": 200, "n_components": 2, "clusterer": "pausing-kmeans"},
        "iod": {"n_particles": 200}, "run": {"predict_every_hours": 3.0}})
    _PausingKMeans.calls = 0
    res = run_scenario(scen, seed=2, registry=reg)
    stepped = [r for r in res.rows if r["kind"] in ("predict", "update")]
    assert stepped and _PausingKMeans.calls >= len(stepped)
    assert min(r["time_predict_s"] for r in stepped) >= PAUSE_S
