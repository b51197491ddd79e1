"""Dense follow-up campaigns (``examples/survey-sets/make_campaign_sets.py``: three sites, every
dark pass, an exposure every 10-20 minutes): the generator's cadence and burn, and, marked slow,
the fit of an NRHO campaign with a 0.5 m/s burn (seed 1), whose burn is found from the least
squares of the filter's first hours without the filter running over every observation."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from cistrack import units
from cistrack.runs.observation_files import read_observations

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples" / "survey-sets"))
from make_campaign_sets import make  # noqa: E402


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("campaign") / "nrho-c1"
    return out, make(out, "nrho", seed=1, burn_ms=0.5)


def test_a_campaign_holds_three_sites_observing_every_10_to_20_minutes_and_its_burn(campaign):
    out, info = campaign
    ms = read_observations(out / "observations.psv", info["epoch"])
    assert len(info["sites"]) == 3 and set(info["per_site"]) <= set(info["sites"])
    t = np.sort(np.asarray(ms.times, dtype=float)) * units.TU_S / 60.0
    steps = np.diff(t)
    assert np.median(steps[steps < 60.0]) < 20.0                    # minutes between exposures within a pass
    burn = info["burn"]
    assert burn["delta_v_ms"] == 0.5 and np.linalg.norm(burn["delta_v_vector_ms"]) == pytest.approx(0.5)
    assert info["first_utc"] < burn["utc"] < info["last_utc"]


@pytest.mark.slow  # about 30 s of CPU
def test_burns_that_explain_the_fit_from_the_first_hours_spare_the_filter_over_every_observation(campaign):
    """The least squares from the filter of the first hours converged looking like a maneuver and
    the burn search explained it: the filter did not run over every observation to seed the same
    search again (it had: 40 of the 110 seconds of a 496-observation campaign's fit)."""
    from cistrack.fitting.from_observations import fit_files

    out, info = campaign
    (one,) = fit_files([out / "observations.psv"], out=out.parent / "fit")
    assert one.ok and one.searched and 0 < one.filter_rows < len(one.run.context.measurements)
    (m,) = json.loads((one.directory / "fit.json").read_text())["maneuvers"]
    z_t = (units.parse_utc(m["t_burn_utc"]) - units.parse_utc(info["burn"]["utc"])).total_seconds() / 86400.0
    assert abs(z_t) <= 3.0 * m["t_burn_sigma_days"] and abs(m["delta_v_ms"] - 0.5) <= 3.0 * m["delta_v_sigma_ms"]
