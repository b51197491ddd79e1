"""``ct.read_fit`` reads a ``cistrack fit`` folder back: its fit.json, checked as export and predict
check it (no documented call had read a fit back; ``read_run`` gives the filter run it started
from, probe K9)."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import cistrack as ct
from cistrack.errors import ConfigError

EXAMPLE = str(Path(__file__).resolve().parents[2] / "core/scenarios/real_data/observations.psv")


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    [one] = ct.fit(EXAMPLE, out=tmp_path_factory.mktemp("fit") / "example", progress=False)
    return one


def test_a_fit_folder_reads_back_as_its_record_with_the_fitted_state(example):
    record = ct.read_fit(example.directory)
    assert record["converged"] is True and record["designation"] == example.designation
    np.testing.assert_array_equal(np.asarray(record["state"], dtype=float), example.result.state)
    assert np.asarray(record["covariance_km"], dtype=float).shape == (6, 6)


def test_a_folder_of_several_objects_fits_names_them(example, tmp_path):
    for name in ("fit-a", "fit-b"):
        shutil.copytree(example.directory, tmp_path / name)
    with pytest.raises(ConfigError, match=r"several objects.*fit-a, fit-b.*read_fit\("):
        ct.read_fit(tmp_path)


def test_a_folder_without_a_fit_is_refused_naming_it(tmp_path):
    with pytest.raises(ConfigError, match="no such directory"):
        ct.read_fit(tmp_path / "nothere")
    with pytest.raises(ConfigError, match="no fit.json"):
        ct.read_fit(tmp_path)
