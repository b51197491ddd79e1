"""Two observatories observing at the same second: every reader keeps both observations (one
filter step of several sites); the same site twice at one time is refused as a duplicate, naming
both lines."""
from __future__ import annotations

import pytest

from cistrack.cli.main import main
from cistrack.errors import MeasurementError
from cistrack.fitting.observation_input import read_object_observations, write_merged
from cistrack.plugin.registry import default_registry
from cistrack.runs.observation_files import read_observations
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
EPOCH = "2026-03-01T00:00:00Z"
PSV_HEAD = "# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
W68 = "cis0001|CCD|W68|2026-03-01T22:35:00.000000Z|140.4858|8.0216|1.0|1.0|Gaia3\n"
MPC_705 = "     K26A01A  C2026 03 01.04167606 51 33.239-07 54 18.29                     705"
TDM_HEAD = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"


def _psv(tmp_path, second_site: str):
    path = tmp_path / "two.psv"
    path.write_text(PSV_HEAD + "X|CCD|705|2026-03-01T01:00:00Z|10|5|1|1|Gaia3\n"
                    f"X|CCD|{second_site}|2026-03-01T01:00:00Z|10.001|5|1|1|Gaia3\n")
    return path


def _tdm_segment(site: str) -> str:
    return (f"META_START\nTIME_SYSTEM = UTC\nPARTICIPANT_1 = {site}\nPARTICIPANT_2 = X\nANGLE_TYPE = AZEL\n"
            "META_STOP\nDATA_START\nANGLE_1 = 2026-03-01T01:00:00 10.5\nANGLE_2 = 2026-03-01T01:00:00 20.5\n"
            "DATA_STOP\n")


def test_an_ades_file_with_two_sites_at_one_time_keeps_both_in_one_time_group(tmp_path):
    ms = read_observations(_psv(tmp_path, "711"), EPOCH)
    assert sorted(ms.sites.tolist()) == ["705", "711"]
    assert [len(g) for g in ms.time_groups()] == [2]


def test_an_ades_file_with_one_site_twice_at_one_time_is_refused_naming_both_lines(tmp_path):
    with pytest.raises(MeasurementError, match=r"two\.psv, line 4, field obsTime: time 2026-03-01T01:00:00\.000000Z "
                                               r"at site '705' repeats the observation of line 3"):
        read_observations(_psv(tmp_path, "705"), EPOCH)


def test_an_mpc_80_column_file_with_two_sites_at_one_time_keeps_both(tmp_path):
    path = tmp_path / "two.obs"
    path.write_text(MPC_705 + "\n" + MPC_705[:77] + "711\n")
    assert sorted(read_observations(path, EPOCH).sites.tolist()) == ["705", "711"]


def test_a_tdm_with_two_stations_at_one_epoch_keeps_both(tmp_path):
    path = tmp_path / "two.tdm"
    path.write_text(TDM_HEAD + _tdm_segment("705") + _tdm_segment("711"))
    assert sorted(read_observations(path, EPOCH).sites.tolist()) == ["705", "711"]


def test_the_merged_file_of_two_files_with_sites_sharing_a_time_reads_back(tmp_path):
    (tmp_path / "w68.psv").write_text(PSV_HEAD + W68)
    registry = default_registry()
    obj = read_object_observations([DATA / "observations.psv", tmp_path / "w68.psv"], registry)[0]
    suffix = write_merged(tmp_path / "observations", obj.measurements, obj.designation, registry)
    assert len(read_observations(tmp_path / f"observations{suffix}", EPOCH)) == 66


@pytest.mark.slow
def test_cistrack_fit_of_two_files_with_sites_sharing_a_time_converges(tmp_path):
    (tmp_path / "w68.psv").write_text(PSV_HEAD + W68)
    out = tmp_path / "out"
    assert main(["fit", str(DATA / "observations.psv"), str(tmp_path / "w68.psv"), "--out", str(out), "--quiet"]) == 0
