"""The built-in realistic campaign end to end (docs/real-data.md): observations of a truth
simulated from two observatories with the real sky, written as IAU ADES and CCSDS TDM, read back,
tracked, and the estimate exported as CCSDS OEM; the run keeps measurement consistency (NIS) and
the exported OEM lies within its reported 3-sigma of the truth."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.evaluation.consistency import run_nis_test
from cistrack.runs.export import export_run
from cistrack.runs.observation_files import read_observations
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.units import parse_utc

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples" / "real-data"))
from make_observations import SITES, make  # noqa: E402

@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("real-data")
    camp = make(d)
    scen = load_scenario("real-data").with_overrides({"measurements": {"file": str(d / "observations.psv"),
                                                                        "reader": {"name": "ades-psv"}}})
    out = d / "run"
    res = run_scenario(scen, output_dir=out)
    return d, camp, scen, out, res


@pytest.mark.slow
def test_ades_and_tdm_files_carry_the_same_observations_from_both_sites(campaign):
    d, camp, scen, _, _ = campaign
    a = read_observations(d / "observations.psv", scen.epoch)
    t = read_observations(d / "observations.tdm", scen.epoch)
    np.testing.assert_array_equal(a.values, t.values)
    np.testing.assert_array_equal(a.values, camp.measurements.values)
    assert set(a.sites.tolist()) == set(SITES) and a.kinds[0] == "radec"


@pytest.mark.slow
def test_the_run_keeps_measurement_consistency(campaign):
    out, res = campaign[3], campaign[4]
    assert res.summary.status == "finished"
    nis = run_nis_test(out, level=0.99)
    assert nis.n >= 20 and nis.within, nis


@pytest.mark.slow
def test_the_exported_oem_lies_within_its_reported_three_sigma_of_the_truth(campaign):
    oem = pytest.importorskip("oem")
    d, camp, scen, out, res = campaign
    path = export_run(out, "oem")
    seg = oem.OrbitEphemerisMessage.open(str(path)).segments[0]
    rows, covs = list(seg.states), [c.matrix for c in seg.covariances]
    frame = res.context.sensor.inertial_frame()
    t = np.array([(parse_utc(r.epoch.isot + "Z") - scen.epoch).total_seconds() for r in rows]) / 375_149.0
    truth = frame.from_synodic(camp.truth_at(t), t)
    last = len(rows) - 1
    e = truth[last] - rows[last].vector
    sd = np.sqrt(np.diag(covs[last]))
    assert np.all(np.abs(e) <= 3.0 * sd), (e, sd)
    assert e @ np.linalg.solve(covs[last], e) <= chi2.ppf(0.9973, 6)


@pytest.mark.parametrize("name", ["observations.psv", "observations.tdm"])
def test_the_bundled_files_hold_the_campaign_of_both_observatories(name):
    from cistrack.scenario.loading import builtin_scenario_path
    scen = load_scenario("real-data")
    folder = builtin_scenario_path("real-data").parent / "real_data"
    ms = read_observations(folder / name, scen.epoch)
    assert set(ms.sites.tolist()) == set(SITES) and set(ms.kinds.tolist()) == {"radec"}
    assert 0 < ms.times[0] and ms.times[-1] < scen.duration
    other = read_observations(folder / "observations.psv", scen.epoch)
    np.testing.assert_array_equal(ms.values, other.values)

