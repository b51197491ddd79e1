"""The real stage 2025-010D (public astrometry of 2025-01 to 2026-05; its final arc before impact
is not used): `cistrack fit` with no option fits the latest arc and its orbit, carried on, meets
the Moon when and where the published solutions say (JPL: 2026-08-05 06:35:40 UTC +- 9 s)."""
import pytest

from cistrack import units
from cistrack.fitting.from_observations import fit_files
from cistrack.least_squares.events import fit_events
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

DEV = builtin_scenario_path("real-data").parent / "real_data" / "2025-010D-dev.psv"
JPL_IMPACT = units.parse_utc("2026-08-05T06:35:40Z")
JPL_SIGMA_S = 9.0


@pytest.fixture(scope="module")
def stage_fit(tmp_path_factory):
    [one] = fit_files([DEV], out=tmp_path_factory.mktemp("stage") / "fit")
    return one


@pytest.mark.slow
def test_the_latest_arc_is_fitted_with_every_observation_and_the_earlier_arcs_laddered(stage_fit):
    one = stage_fit
    assert one.ok and one.result.n_rejected <= 0.05 * (one.result.n_used + one.result.n_rejected)
    assert one.arcs is not None and len(one.arcs.ladder) == 2
    assert one.determination.sentence.startswith("well determined")


@pytest.mark.slow
def test_the_radiation_pressure_is_estimated_and_physical(stage_fit):
    value, sigma = stage_fit.result.parameter("area_to_mass_m2_kg")
    assert 0.002 < value < 0.03 and value / sigma > 5


@pytest.mark.slow
def test_the_orbit_reaches_the_moon_at_the_published_time(stage_fit):
    one = stage_fit
    hits = [e for e in fit_events(one.run.context.dynamics, one.result, days=80.0, epoch=one.scenario.epoch)
            if e.kind == "impact"]
    assert [h.body for h in hits] == ["Moon"]
    dt = (units.parse_utc(hits[0].utc) - JPL_IMPACT).total_seconds()
    assert abs(dt) <= 3 * (hits[0].sigma["time_s"] ** 2 + JPL_SIGMA_S ** 2) ** 0.5
