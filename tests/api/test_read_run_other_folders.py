"""ct.read_run on a folder that holds something else cistrack wrote says what it holds (probe H13)."""
from __future__ import annotations

import json

import pytest

import cistrack as ct
from cistrack.errors import ConfigError


def test_a_folder_of_several_objects_fits_names_them_and_the_call_to_make(tmp_path):
    for name in ("fit-cis0001", "fit-cis0002"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "fit.json").write_text(json.dumps({"format": "cistrack-fit", "version": 1}))
    with pytest.raises(ConfigError, match=r"fits of several objects, one folder each \(fit-cis0001, fit-cis0002\): "
                                          r"read_run one of those"):
        ct.read_run(tmp_path)


def test_a_study_folder_points_to_its_runs_and_ct_study(tmp_path):
    (tmp_path / "study.json").write_text("{}")
    with pytest.raises(ConfigError, match=r"a study's runs \(study.json\): read_run one of its runs' folders, or ct.study"):
        ct.read_run(tmp_path)


def test_an_empty_folder_is_only_not_a_run_s_results_folder(tmp_path):
    with pytest.raises(ConfigError, match=r"not a run's results folder \(no manifest.json\)$"):
        ct.read_run(tmp_path)
