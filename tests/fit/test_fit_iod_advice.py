"""When a fit fails because its IOD cannot start, the IOD's advice names its own parameters
(``lower min_fit/order``), as a scenario file's ``[iod]`` keys; ``cistrack fit`` sets them with
``--set iod.NAME=VALUE``, and its message says so, for the user's IOD and for the ranging IOD it
fell back on (which is chosen with ``--set iod.name=...`` first)."""
from __future__ import annotations

from cistrack.fitting.from_observations import fit_files
from cistrack.scenario.loading import builtin_scenario_path

SHIPPED = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
SPARSE_ROWS = (0, 6, 10, 14, 19, 22, 25, 30, 34)
"""Observations of the shipped file more than 1.5 h apart: a first pass of one (before a gap over
3 h; the kinematic IOD needs 8) and no tracklet of 3 (the ranging IOD's min_tracklet)."""


def _sparse_file(tmp_path):
    lines = SHIPPED.read_text().splitlines()
    path = tmp_path / "sparse.psv"
    path.write_text("\n".join(lines[:2] + [lines[2 + i] for i in SPARSE_ROWS]) + "\n")
    return path


def _failure(tmp_path, settings=()) -> str:
    [one] = fit_files([_sparse_file(tmp_path)], out=tmp_path / "fit", settings=list(settings), progress=False)
    assert not one.ok
    return " ".join(one.failure.split())


def test_the_template_iods_advice_names_the_set_options_of_its_parameters(tmp_path):
    assert ("lower min_fit/order (in cistrack fit: --set iod.min_fit=..., --set iod.order=...)."
            in _failure(tmp_path))


def test_the_advice_of_the_ranging_iod_fallen_back_on_says_to_choose_it_first(tmp_path):
    assert ("lower min_tracklet or observe longer (in cistrack fit: --set iod.name=tracklet-ranging "
            "--set iod.min_tracklet=...)" in _failure(tmp_path))


def test_a_parameter_the_advice_names_but_the_iod_has_not_is_not_offered(tmp_path):
    """Gauss's method shares the kinematic IOD's first-pass selection, whose advice names `order`."""
    failure = _failure(tmp_path, ["iod.name=gauss"])
    assert "lower min_fit/order (in cistrack fit: --set iod.min_fit=...)." in failure
    assert "--set iod.order" not in failure
