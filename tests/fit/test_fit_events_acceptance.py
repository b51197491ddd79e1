"""The shipped real-data example (simulated, so its truth is known): the orbit fitted by
`cistrack fit` hits the Moon on 2026-03-17, and the impact it reports (time, selenographic site)
lies within 3 sigma of the truth's own impact."""
import numpy as np
import pytest

from cistrack import units
from cistrack.fitting.from_observations import fit_files
from cistrack.least_squares.events import fit_events, orbit_events
from cistrack.plugin.registry import default_registry
from cistrack.results.estimates import KM_SCALE
from cistrack.scenario.builtin_scenarios import builtin_scenario_path


def _truth_impact():
    path = builtin_scenario_path("real-data").parent / "real_data" / "truth.csv"
    first = path.read_text().splitlines()[2].split(",")
    x0 = np.array([float(v) for v in first[1:7]]) / KM_SCALE
    dyn = default_registry().create("dynamics", "ephemeris", epoch=first[0])
    [hit] = [e for e in orbit_events(dyn, x0, None, 0.0, units.days_to_tu(20.0)) if e.kind == "impact"]
    return hit


@pytest.mark.slow
def test_the_fitted_orbit_reports_the_truths_lunar_impact(tmp_path):
    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    [one] = fit_files([obs], out=tmp_path / "fit")
    assert one.ok
    [hit] = [e for e in fit_events(one.run.context.dynamics, one.result, days=14.0, epoch=one.scenario.epoch)
             if e.kind == "impact"]
    truth = _truth_impact()
    assert hit.body == truth.body == "Moon"
    dt = (units.parse_utc(hit.utc) - units.parse_utc(truth.utc)).total_seconds()
    assert abs(dt) < 3 * hit.sigma["time_s"]
    assert abs(hit.latitude_deg - truth.latitude_deg) < 3 * hit.sigma["latitude_deg"]
    assert abs(hit.longitude_deg - truth.longitude_deg) < 3 * hit.sigma["longitude_deg"]
    assert abs(hit.speed_kms - truth.speed_kms) < 1e-3


@pytest.mark.slow
def test_an_export_past_the_impact_ends_at_it_and_names_it_in_utc(tmp_path):
    import re

    from cistrack.fitting.fit_export import export_fit

    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    [one] = fit_files([obs], out=tmp_path / "fit")
    out = export_fit(one.directory, "oem", tmp_path / "past.oem", predict_days=20.0)
    text = out.read_text()
    assert "impact (Moon) 2026-03-17T" in text
    assert not re.search(r"\d TU\b", text)  # never an internal time
    last = [ln.split()[0] for ln in text.splitlines() if ln[:4].isdigit()][-1]
    [hit] = [e for e in fit_events(one.run.context.dynamics, one.result, days=20.0, epoch=one.scenario.epoch)
             if e.kind == "impact"]
    assert 0 <= (units.parse_utc(hit.utc) - units.parse_utc(last + "Z")).total_seconds() < 600
