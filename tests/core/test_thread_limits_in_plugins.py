"""``$CISTRACK_NUM_THREADS`` bounds the OpenMP and BLAS thread pools of the whole run, the calls
into plugins included (a plugin's scikit-learn, loaded before the run or first inside it)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from cistrack.api import hookimpl
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.threads import library_thread_limit

SMALL = {"iod": {"n_particles": 200}, "filter": {"n_particles": 200, "n_components": 2}, "duration_days": 1.5}


def _most_threads(api: str) -> int:
    """The largest thread count of the loaded libraries of ``api`` ("openmp" or "blas")."""
    return max(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == api)


class ThreadWatcher:
    """An observer plugin: at each of its calls it notes the most OpenMP and BLAS threads."""

    def __init__(self):
        self.seen: list[tuple[int, int]] = []

    @hookimpl
    def cistrack_step_updated(self, run, step):
        self.seen.append((_most_threads("openmp"), _most_threads("blas")))


@pytest.fixture
def openmp_loaded():
    """scikit-learn's OpenMP and BLAS libraries loaded, each allowed 2 threads outside the run."""
    import sklearn.cluster  # noqa: F401  (loads scikit-learn's OpenMP runtime)

    with threadpool_limits(limits=2):
        yield


def test_plugin_calls_in_a_run_use_at_most_cistrack_num_threads(openmp_loaded, monkeypatch):
    monkeypatch.setenv("CISTRACK_NUM_THREADS", "1")
    reg = load_registry()
    watcher = ThreadWatcher()
    res = run_scenario(load_scenario("quick", overrides=SMALL, registry=reg), seed=1, registry=reg,
                       observers=[watcher])
    assert res.summary.status == "finished"
    assert watcher.seen and set(watcher.seen) == {(1, 1)}


def test_the_run_hands_the_libraries_their_thread_counts_back(openmp_loaded, monkeypatch):
    monkeypatch.setenv("CISTRACK_NUM_THREADS", "1")
    reg = load_registry()
    run_scenario(load_scenario("quick", overrides=SMALL, registry=reg), seed=1, registry=reg)
    assert (_most_threads("openmp"), _most_threads("blas")) == (2, 2)


def test_a_limit_set_around_the_run_is_never_raised(openmp_loaded, monkeypatch):
    monkeypatch.setenv("CISTRACK_NUM_THREADS", "2")
    with threadpool_limits(limits=1), library_thread_limit():
        assert _most_threads("openmp") == 1


def test_a_clusterers_all_cores_setting_stays_within_the_run_limit(openmp_loaded, monkeypatch):
    from cistrack.plugins.clustering.thread_limits import limited_threads

    monkeypatch.setenv("CISTRACK_NUM_THREADS", "1")
    with limited_threads(0):  # n_threads = 0 of kmeans, gmm and bic: "all cores"
        assert _most_threads("openmp") == 1
    assert _most_threads("openmp") == 2


LATE_IMPORT = textwrap.dedent("""
    from threadpoolctl import threadpool_info
    from cistrack.threads import library_thread_limit

    def openmp():
        return max(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "openmp")

    with library_thread_limit():
        import sklearn.cluster  # first loaded inside the run, as a plugin's first call does
        inside = openmp()
    print(inside, openmp())
""")


def test_a_library_first_loaded_inside_the_run_is_limited_then_given_back():
    env = {**os.environ, "CISTRACK_NUM_THREADS": "1", "OMP_NUM_THREADS": "3"}
    out = subprocess.run([sys.executable, "-c", LATE_IMPORT], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["1", "3"]
