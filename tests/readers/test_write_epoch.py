"""write_observations refuses an epoch other than the one the measurements' times count from (it
had silently moved every time tag by the difference, years in one case)."""
from __future__ import annotations

import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations, write_observations
from cistrack.scenario.loading import builtin_scenario_path

OBS = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
EPOCH = "2026-03-01T00:00:00Z"


def test_the_epoch_they_were_read_with_writes_them_back_unchanged(tmp_path):
    m = read_observations(OBS, epoch=EPOCH)
    write_observations(tmp_path / "w.psv", m, epoch="2026-03-01T00:00:00.000000Z")
    again = read_observations(tmp_path / "w.psv", epoch=EPOCH)
    assert abs(again.times - m.times).max() < 1e-9


@pytest.mark.parametrize("suffix", ["psv", "tdm"])
def test_another_epoch_is_refused_naming_the_one_to_pass(tmp_path, suffix):
    m = read_observations(OBS, epoch=EPOCH)
    with pytest.raises(MeasurementError, match=r"epoch=2020-01-01T00:00:00Z: the measurements' times are counted from "
                                               r"2026-03-01T00:00:00"):
        write_observations(tmp_path / f"w.{suffix}", m, epoch="2020-01-01T00:00:00Z")
    assert not (tmp_path / f"w.{suffix}").exists()


def test_a_list_of_paths_is_refused_by_name():
    with pytest.raises(MeasurementError, match="path=list: give the path of one observation file"):
        read_observations([OBS], epoch=EPOCH)
