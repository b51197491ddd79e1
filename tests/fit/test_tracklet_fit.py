"""`cistrack fit` from survey-cadence files (a lone first tracklet of 3-5 exposures, uneven nights,
two sites in both hemispheres, 3 % gross outliers): no option, the tracklet-ranging IOD seeds the
least squares, the fit converges, the truth lies inside the fit's covariance (scaled as the export
scales it) all along the arc and the outliers are rejected. Campaigns: tests/fit/tracklet_campaign.py."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cistrack import units
from cistrack.fitting.from_observations import fit_files
from cistrack.least_squares.prediction import predict_orbit

from .tracklet_campaign import heo_state_km, survey_campaign

M2_BOUND = 22.5     # chi-square, 6 degrees of freedom, 99.9 %


def _catalog_km(name: str) -> np.ndarray:
    from cistrack.api import default_registry

    return units.state_to_km(np.asarray(default_registry().create("orbit", name).state, dtype=float))


def _truth_m2(one, camp) -> float:
    """Largest Mahalanobis squared of the truth under the fit's covariance (times the noise scale
    squared when above 1, as exported) at 40 epochs over the arc."""
    r, dyn = one.result, one.run.context.dynamics
    ms = one.run.context.measurements
    times = np.linspace(ms.times[0], ms.times[-1], 40)
    t0 = (camp.epoch - one.scenario.epoch).total_seconds() / units.TU_S
    truth = dyn.propagate(camp.x0[None], t0, times).states[:, 0]
    scaled = replace(r, covariance=r.covariance * max(1.0, r.noise_scale) ** 2)
    pred = predict_orbit(scaled, dyn, times)
    e = truth - pred.states
    return float(max(ei @ np.linalg.solve(p, ei) for ei, p in zip(e, pred.covariances)))


def _rejected_utc(one) -> set[str]:
    res = one.result.residuals
    return {units.format_utc(units.tu_to_utc(one.scenario.epoch, float(t)))[:19]
            for t, k in zip(res.times, res.rejected) if k}


CASES = [("dro-2-1", "2026-03-02T00:00:00Z", ("J04", "W68"), 4901),
         ("nrho-9-2", "2026-05-10T00:00:00Z", ("568", "809"), 4902),
         ("heo", "2026-03-01T00:00:00Z", ("G96", "Q62"), 4903)]


@pytest.mark.slow
@pytest.mark.parametrize("orbit, epoch, sites, seed", CASES, ids=[c[0] for c in CASES])
def test_survey_file_fits_with_no_option(tmp_path, orbit, epoch, sites, seed):
    state = heo_state_km() if orbit == "heo" else _catalog_km(orbit)
    camp = survey_campaign(tmp_path / "data", state, epoch, sites, seed)
    [one] = fit_files([camp.path], out=tmp_path / "fit")
    assert one.ok, one.failure or one.result.messages
    assert one.seeding["method"] == "tracklet-ranging"
    assert any("seeded by the IOD 'tracklet-ranging'" in m for m in one.result.messages)
    assert _truth_m2(one, camp) <= M2_BOUND
    assert set(camp.outliers) <= _rejected_utc(one)
    assert one.result.n_rejected <= len(camp.outliers) + 2


@pytest.mark.slow
def test_one_night_says_the_orbit_is_poorly_determined(tmp_path):
    camp = survey_campaign(tmp_path / "data", _catalog_km("dro-2-1"), "2026-03-02T00:00:00Z", ("J04",), 4904,
                           days=1.0, first_night=3)
    [one] = fit_files([camp.path], out=tmp_path / "fit")
    assert one.result is not None
    assert any("seeded by the IOD" in m for m in one.result.messages)
    assert any("the orbit is poorly determined" in m for m in one.result.messages)
