"""A fit does its least squares with one BLAS thread, as a run does its filter, called from Python
as from the command line (whose executable loads BLAS with one thread): its matrices are small,
and a pool of BLAS threads only spins over them (an 881-observation campaign's burn screen took
2.6 ms per 1762 x 9 least-squares solve with two threads, 0.1 ms with one)."""
from __future__ import annotations

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from cistrack.fitting.from_observations import fit_files
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"


def _most_blas_threads() -> int:
    return max(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas")


@pytest.fixture
def two_blas_threads():
    """BLAS allowed 2 threads outside the fit."""
    with threadpool_limits(limits=2, user_api="blas"):
        yield


def test_the_least_squares_of_a_fit_from_python_use_one_blas_thread(tmp_path, two_blas_threads):
    lines = (DATA / "observations.psv").read_text().splitlines()
    path = tmp_path / "short.psv"
    path.write_text("\n".join(lines[:2 + 40]) + "\n")
    seen: list[tuple[str, int]] = []
    fit_files([path], out=tmp_path / "fit", settings=["iod.n_particles=300", "filter.n_particles=300"],
              log=lambda m: seen.append((m, _most_blas_threads())))
    during = {n for m, n in seen if "least squares" in m}
    assert during == {1}
    assert _most_blas_threads() == 2  # given back
