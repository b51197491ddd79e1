"""An event's 1-sigma carries the uncertainty of the solve-for parameters (the area-to-mass
ratio) when the fit estimated them: the linear mapping of the joint covariance of state and
parameter, checked against draws of both."""
import numpy as np
import pytest

from cistrack import units
from cistrack.least_squares.events import ParameterSpread, event_values, orbit_events
from cistrack.plugin.registry import default_registry
from cistrack.results.estimates import KM_SCALE
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

AMR, AMR_SIGMA = 0.01, 0.004  # m^2/kg: a hollow stage's C_R A/m, known to 40 %
STATE_SIGMA = np.array([1e-2, 1e-2, 1e-2, 1e-7, 1e-7, 1e-7]) / KM_SCALE  # 10 m, 0.01 cm/s: the ratio dominates


def _impacting_orbit():
    """The shipped example's truth, which hits the Moon on 2026-03-17, with radiation pressure."""
    path = builtin_scenario_path("real-data").parent / "real_data" / "truth.csv"
    first = path.read_text().splitlines()[2].split(",")
    dyn = default_registry().create("dynamics", "ephemeris", epoch=first[0]).with_parameters(area_to_mass_m2_kg=AMR)
    return dyn, np.array([float(v) for v in first[1:7]]) / KM_SCALE


def _spread(amr_sigma: float) -> ParameterSpread:
    cov = np.diag(np.concatenate([STATE_SIGMA, [amr_sigma]]) ** 2)
    return ParameterSpread(cov, ("area_to_mass_m2_kg",), np.array([AMR]))


def _impact(dyn, x0, covariance):
    [hit] = [e for e in orbit_events(dyn, x0, covariance, 0.0, units.days_to_tu(20.0), approaches=False)
             if e.kind == "impact"]
    return hit


def test_a_parameter_known_exactly_adds_nothing_to_the_sigma():
    dyn, x0 = _impacting_orbit()
    with_state_only = _impact(dyn, x0, np.diag(STATE_SIGMA ** 2)).sigma["time_s"]
    with_exact_parameter = _impact(dyn, x0, _spread(1e-12)).sigma["time_s"]
    assert with_exact_parameter == pytest.approx(with_state_only, rel=1e-3)


def test_an_uncertain_parameter_widens_the_impact_time_sigma():
    dyn, x0 = _impacting_orbit()
    assert _impact(dyn, x0, _spread(AMR_SIGMA)).sigma["time_s"] > 1.5 * _impact(dyn, x0, _spread(1e-12)).sigma["time_s"]


@pytest.mark.slow
def test_the_linear_sigma_matches_draws_of_state_and_parameter():
    dyn, x0 = _impacting_orbit()
    hit = _impact(dyn, x0, _spread(AMR_SIGMA))
    rng = np.random.default_rng(2611)
    times = []
    for _ in range(150):
        x = x0 + STATE_SIGMA * rng.standard_normal(6)
        d = dyn.with_parameters(area_to_mass_m2_kg=AMR + AMR_SIGMA * rng.standard_normal())
        times.append(event_values(d, x[None], 0.0, "impact", "Moon", (0.0, units.days_to_tu(20.0)))[0, 0])
    drawn = float(np.std(times, ddof=1)) * units.TU_S
    assert drawn == pytest.approx(hit.sigma["time_s"], rel=0.2)
