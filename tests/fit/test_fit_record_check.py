"""A fit.json whose orbit fields are not what a fit writes is refused by name (predict and export
read it through read_fit_record): never a traceback from numpy or datetime, never NaN predictions."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.fitting.fit_record import read_fit_record


def _record() -> dict:
    """The orbit fields of a fit record as a fit writes them (a correlated, positive-definite covariance;
    the UTC times the scenario's epoch plus their TU)."""
    from cistrack import units

    a = np.arange(36, dtype=float).reshape(6, 6) / 36.0
    cov = 1e-10 * (a @ a.T + np.eye(6))
    start = units.tu_to_utc(units.parse_utc("2026-03-06T12:02:32.999088Z"), -1.05)
    return {"format": "cistrack-fit", "designation": "C2RLB52", "state": [1.02, 0.0, -0.18, 0.0, -0.1, 0.0],
            "covariance": cov.tolist(), "epoch_tu": 1.05, "epoch_utc": "2026-03-06T12:02:32.999088Z",
            "scenario_epoch_utc": units.format_utc(start),
            "noise_scale": 1.1, "rms": 1.07, "chi2": 150.6, "condition_number": 445.7, "n_used": 65,
            "n_rejected": 0, "iterations": 5, "converged": True, "weakest_direction_km": [2.3, -0.3, -0.5, 0, 0, 0],
            "area_to_mass": {"estimated": False},
            "arc": {"first_tu": 0.0, "last_tu": 1.05, "first_utc": units.format_utc(start),
                    "last_utc": "2026-03-06T12:02:32.999088Z"},
            "maneuvers": [_burn()]}


def _burn() -> dict:
    return {"t_days": 2.1, "t_burn_days": 2.0, "t_burn_sigma_days": 0.05, "delta_v_ms": 0.5, "delta_v_sigma_ms": 0.05,
            "delta_v_vector_ms": [0.3, 0.4, 0.0], "delta_v_covariance_ms2": (np.eye(3) * 0.0025).tolist()}


def _written(tmp_path, record: dict):
    (tmp_path / "fit.json").write_text(json.dumps(record))
    return tmp_path


def _tampered(field: str, value) -> dict:
    rec = _record()
    if field.startswith("covariance["):
        i, j = (int(c) for c in field[len("covariance["):-1].split(","))
        rec["covariance"][i][j] = value
    else:
        rec[field] = value
    return rec


def test_a_record_as_a_fit_writes_it_is_read(tmp_path):
    assert read_fit_record(_written(tmp_path, _record()))["designation"] == "C2RLB52"


def test_an_undefined_noise_scale_is_allowed(tmp_path):
    assert math.isnan(read_fit_record(_written(tmp_path, _tampered("noise_scale", float("nan"))))["noise_scale"])


def test_an_undefined_number_written_as_null_reads_back_as_nan(tmp_path):
    rec = read_fit_record(_written(tmp_path, _tampered("noise_scale", None)))
    assert math.isnan(rec["noise_scale"])


def test_fit_json_numbers_are_strict_json():
    """NaN and infinities, which strict JSON readers (jq, JavaScript) refuse, are written as null."""
    from cistrack.results.strict_json import finite_or_null

    data = {"noise_scale": float("nan"), "rejection_threshold": np.inf, "sigmas": np.array([1.0, -np.inf]),
            "nested": [{"x": np.float64("nan"), "n": 3, "ok": 2.5}]}
    text = json.dumps(finite_or_null(data), allow_nan=False)
    assert json.loads(text) == {"noise_scale": None, "rejection_threshold": None, "sigmas": [1.0, None],
                                "nested": [{"x": None, "n": 3, "ok": 2.5}]}


@pytest.mark.parametrize("field, value, named", [
    ("state", "abc", "'state'"),
    ("state", [1, 2, 3, 4, 5], "'state'"),
    ("state", [1, 2, 3, 4, 5, float("nan")], "'state'"),
    ("epoch_tu", "x", "'epoch_tu'"),
    ("epoch_tu", 1e6, "'epoch_tu'"),
    ("epoch_utc", None, "'epoch_utc'"),
    ("epoch_utc", "2026-13-45T99:00:00Z", "'epoch_utc'"),
    ("noise_scale", "x", "'noise_scale'"),
    ("noise_scale", -2.0, "'noise_scale'"),
    ("noise_scale", float("inf"), "'noise_scale'"),
    ("n_used", 6.5, "'n_used'"),
    ("converged", "yes", "'converged'"),
    ("covariance[0,0]", float("nan"), "'covariance'"),
    ("covariance[0,0]", float("inf"), "'covariance'"),
    ("covariance[0,0]", -1.0, "positive semi-definite"),
    ("covariance[0,1]", 1.0, "not symmetric"),
    ("covariance", [[0.0] * 6] * 6, "'covariance'"),
    ("area_to_mass", {"estimated": True, "value_m2_kg": "big"}, "'area_to_mass.value_m2_kg'"),
])
def test_an_orbit_field_a_fit_never_writes_is_refused_by_name(tmp_path, field, value, named):
    with pytest.raises(ConfigError, match="fit.json: field ") as exc:
        read_fit_record(_written(tmp_path, _tampered(field, value)))
    assert named in str(exc.value)


@pytest.mark.parametrize("state, words", [
    ([1e30] * 6, "within 3e+06 km of the Earth-Moon barycentre"),
    ([8.0, 0.0, 0.0, 0.0, 0.0, 0.0], "within 3e+06 km"),       # 3.1 million km out
    ([1.02, 0.0, -0.18, 0.0, 100.0, 0.0], "slower than 100 km/s"),
])
def test_a_state_no_fit_writes_is_refused_naming_the_field(tmp_path, state, words):
    with pytest.raises(ConfigError, match=r"field 'state' must be a synodic state") as err:
        read_fit_record(_written(tmp_path, _tampered("state", state)))
    assert words in str(err.value)


def test_a_fit_refused_as_not_cislunar_keeps_its_far_state_readable(tmp_path):
    rec = _tampered("state", [8.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    rec["converged"] = False
    assert read_fit_record(_written(tmp_path, rec))["state"][0] == 8.0


@pytest.mark.parametrize("value", [None, 12345, "garbage", [0.0, 1.0], {"first_tu": 2.0, "last_tu": 1.0},
                                   {"first_tu": "x", "last_tu": 1.0}])
def test_an_arc_that_is_not_a_table_of_its_times_is_refused(tmp_path, value):
    rec = _record()
    if value is None:
        del rec["arc"]
    else:
        rec["arc"] = value
    with pytest.raises(ConfigError, match="field 'arc"):
        read_fit_record(_written(tmp_path, rec))


@pytest.mark.parametrize("edit", [{"t_burn_sigma_days": -1.0}, {"t_burn_sigma_days": 0.0}, {"t_burn_days": float("nan")},
                                  {"t_burn_days": 9.0}, {"t_days": "x"}, {"delta_v_vector_ms": [1.0]},
                                  {"delta_v_covariance_ms2": [[1.0]]}, {"delta_v_ms": -0.5}, {"delta_v_ms": 1e300},
                                  {"t_burn_utc": "junk"}, {"t_burn_window_days": [2.5, 1.5]}])
def test_a_burn_that_no_fit_writes_is_refused(tmp_path, edit):
    """Burn times up to the fit's epoch (1.05 TU, 4.56 days) with a positive sigma: a negative one had
    made the OEM start three days before the burn."""
    rec = _record()
    rec["maneuvers"] = [{**_burn(), **edit}]
    with pytest.raises(ConfigError, match="field 'maneuvers"):
        read_fit_record(_written(tmp_path, json.loads(json.dumps(rec).replace("NaN", "NaN"))))


@pytest.mark.parametrize("value", [None, "x", [1]])
def test_a_verdict_that_is_not_a_table_is_refused(tmp_path, value):
    with pytest.raises(ConfigError, match="field 'determination' must be a table"):
        read_fit_record(_written(tmp_path, _tampered("determination", value)))


@pytest.mark.parametrize("field", ["horizon_days", "covariance_horizon_days"])
@pytest.mark.parametrize("value", [-5, "x", [1], 1e400])
def test_a_horizon_that_is_not_days_is_refused(tmp_path, field, value):
    """Exports and predictions warn past the horizons: a NaN or text one had silently dropped the warning."""
    rec = {**_record(), "determination": {"horizon_days": 8.0, "covariance_horizon_days": 3.0, field: value}}
    with pytest.raises(ConfigError, match=f"field 'determination.{field}'"):
        read_fit_record(_written(tmp_path, rec))


def test_a_verdict_with_unmeasured_horizons_is_read(tmp_path):
    rec = {**_record(), "determination": {"horizon_days": None, "covariance_horizon_days": None}}
    assert read_fit_record(_written(tmp_path, rec))["determination"]["horizon_days"] is None


def test_maneuvers_that_are_not_a_list_are_refused(tmp_path):
    with pytest.raises(ConfigError, match="field 'maneuvers' must be a list of burns"):
        read_fit_record(_written(tmp_path, _tampered("maneuvers", 12345)))


def test_a_covariance_whose_sigmas_reach_beyond_cislunar_space_is_refused(tmp_path):
    """Finite and positive definite, 1e300 on its diagonal: propagation had divided by zero."""
    rec = _record()
    rec["covariance"] = (np.eye(6) * 1e300).tolist()
    with pytest.raises(ConfigError, match="sigmas stay within"):
        read_fit_record(_written(tmp_path, rec))


def test_a_fit_refused_as_undetermined_keeps_its_wide_covariance_readable(tmp_path):
    """The fit writes such a record (not converged: sigmas beyond 3e6 km); export and predict then
    say why it is not an orbit rather than calling the file one cistrack did not write."""
    rec = _record()
    rec["covariance"], rec["converged"] = (np.eye(6) * 1e2).tolist(), False
    assert read_fit_record(_written(tmp_path, rec))["converged"] is False


def test_a_covariance_that_overflows_is_refused_even_when_the_fit_did_not_converge(tmp_path):
    rec = _record()
    rec["covariance"], rec["converged"] = (np.eye(6) * 1e300).tolist(), False
    with pytest.raises(ConfigError, match="stay finite"):
        read_fit_record(_written(tmp_path, rec))


def test_an_epoch_beyond_the_ephemeris_is_refused(tmp_path):
    with pytest.raises(ConfigError, match="field 'epoch_tu'"):
        read_fit_record(_written(tmp_path, _tampered("epoch_tu", 9.0e4)))


def test_a_record_nested_beyond_any_fit_record_is_refused(tmp_path):
    (tmp_path / "fit.json").write_text("[" * 100000)
    with pytest.raises(ConfigError, match="cannot be read"):
        read_fit_record(tmp_path)


def _with_scenario_epoch(epoch_utc: str) -> dict:
    from cistrack import units

    rec = _record()
    start = units.tu_to_utc(units.parse_utc(rec["epoch_utc"]), -rec["epoch_tu"])
    rec["scenario_epoch_utc"], rec["epoch_utc"] = units.format_utc(start), epoch_utc
    return rec


def test_an_epoch_utc_that_is_the_scenarios_epoch_plus_epoch_tu_is_read(tmp_path):
    assert read_fit_record(_written(tmp_path, _with_scenario_epoch("2026-03-06T12:02:32.999088Z")))


def test_an_epoch_utc_that_the_scenarios_epoch_and_epoch_tu_contradict_is_refused(tmp_path):
    """An edited epoch_utc a year later had been exported as the OEM's stated fit epoch."""
    with pytest.raises(ConfigError, match="field 'epoch_utc' must be a UTC time as text, the scenario's epoch"):
        read_fit_record(_written(tmp_path, _with_scenario_epoch("2027-03-06T12:02:32.999088Z")))
