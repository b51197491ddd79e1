"""The Python API names the argument whose type it does not take, before anything runs."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cistrack as ct


@pytest.mark.parametrize("call, argument", [
    (lambda: ct.run("quick", settings=5), "settings=5"),
    (lambda: ct.run("quick", settings=[1, 2]), "settings=[1, 2]"),
    (lambda: ct.run("quick", log=5), "log=5"),
    (lambda: ct.run("quick", out=3.5), "out=3.5"),
    (lambda: ct.fit(5), "files=5"),
    (lambda: ct.fit([]), "files=[]"),
    (lambda: ct.fit("ok.psv", out=3.5), "out=3.5"),
    (lambda: ct.read_run(5), "directory=5"),
    (lambda: ct.study(5), "study=5"),
    (lambda: ct.run(None), "scenario=None"),
    (lambda: ct.run(123), "scenario=123"),
    (lambda: ct.load_scenario({}), "scenario={}"),
    (lambda: ct.run("quick", registry="x"), "registry='x'"),
    (lambda: ct.load_scenario("quick", registry=3), "registry=3"),
    (lambda: ct.fit("ok.psv", registry={}), "registry={}"),
    (lambda: ct.fit("ok.psv", progress="no"), "progress='no'"),
    (lambda: ct.run("quick", progress=1), "progress=1"),
    (lambda: ct.run("quick", out="somewhere", overwrite="no"), "overwrite='no'"),  # a true string: had replaced
    (lambda: ct.fit("ok.psv", overwrite="false"), "overwrite='false'"),
])
def test_a_wrong_argument_type_is_a_type_error_naming_it(call, argument):
    with pytest.raises(TypeError, match=argument.replace("[", r"\[").replace("]", r"\]")):
        call()


@pytest.mark.parametrize("call, argument", [
    (lambda: ct.run("quick", out=""), "out=''"),
    (lambda: ct.fit("ok.psv", out=" "), "out=' '"),
    (lambda: ct.study("quick-comparison", out=""), "out=''"),
    (lambda: ct.read_run(""), "directory=''"),
])
def test_a_blank_path_is_refused_naming_it_not_taken_for_the_current_or_default_folder(call, argument, tmp_path,
                                                                                    monkeypatch):
    """out='' had written a run's or fit's results into the current folder, and a study into its default one."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ct.ConfigError, match=f"^{argument} is empty; give a path"):
        call()
    assert list(tmp_path.iterdir()) == []


def test_settings_as_a_mapping_or_a_list_of_strings_are_taken():
    assert ct.load_scenario("quick", settings={"duration_days": 1.5}).duration_days == 1.5
    assert ct.load_scenario("quick", settings=["duration_days=1.5"]).duration_days == 1.5


@pytest.mark.parametrize("value, expected", [(np.int64(500), 500), (np.int32(700), 700)])
def test_a_numpy_integer_setting_is_taken_as_the_integer_it_holds(value, expected):
    assert ct.load_scenario("quick", settings={"iod.n_particles": value}).components["iod"].params["n_particles"] == expected


def test_a_numpy_float_setting_is_taken_as_the_number_it_holds():
    assert ct.load_scenario("quick", settings={"duration_days": np.float32(1.5)}).duration_days == 1.5


def test_a_path_setting_is_taken_as_its_string():
    scenario = ct.load_scenario("real-data", settings={"measurements.file": Path("real_data/observations.psv")})
    assert scenario.measurements_file.name == "observations.psv"


@pytest.mark.parametrize("value", [object(), None, np.array([1, 2])])
def test_a_setting_that_is_no_value_is_refused_saying_what_is_taken(value):
    with pytest.raises(ct.ConfigError, match=r"settings\['duration_days'\] = .*: not a setting value \(give a number"):
        ct.load_scenario("quick", settings={"duration_days": value})


@pytest.mark.parametrize("files", [
    lambda: (p for p in ["missing.psv"]),
    lambda: np.array(["missing.psv"]),
    lambda: iter([Path("missing.psv")]),
])
def test_fit_takes_any_iterable_of_paths_as_its_signature_says(files, tmp_path, monkeypatch):
    """A generator or a numpy array of paths had been a TypeError (probe J9): here they reach the
    file, which is missing."""
    from cistrack.errors import ConfigError

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match="observation file missing.psv: no such file"):
        ct.fit(files(), progress=False)


@pytest.mark.parametrize("files", [{"a.psv": 1}, [b"a.psv"], (p for p in [])])
def test_fit_refuses_a_mapping_bytes_or_an_empty_iterable_naming_files(files):
    with pytest.raises(TypeError, match="files=.*: give a path .* or a non-empty iterable of paths"):
        ct.fit(files)
