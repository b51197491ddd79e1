"""An export refuses a run folder while a 'cistrack run --overwrite' replacing it holds its lock:
the new run takes the lock before it writes its manifest, and the export had written the orbit of
the finished run being replaced (OBJECT_ID of the old run) with exit 0."""
from __future__ import annotations

import pytest

import cistrack as ct
from cistrack.errors import CistrackError
from cistrack.results.dir_lock import run_lock
from cistrack.runs.export import export_run

SHORT = {"duration_days": 1.2}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    d = tmp_path_factory.mktemp("run") / "r"
    ct.run("quick", settings=SHORT, out=d)
    return d


def test_a_finished_run_being_replaced_is_not_exported(finished, tmp_path):
    with run_lock(finished):
        with pytest.raises(CistrackError, match="'cistrack run'.*is writing its results in this directory"):
            export_run(finished, format="oem", path=tmp_path / "x.oem")
    assert not (tmp_path / "x.oem").exists()


def test_not_even_with_force(finished, tmp_path):
    with run_lock(finished):
        with pytest.raises(CistrackError, match="is writing its results"):
            export_run(finished, format="oem", path=tmp_path / "x.oem", force=True)


def test_once_the_lock_is_released_it_exports(finished, tmp_path):
    assert export_run(finished, format="oem", path=tmp_path / "x.oem").is_file()
