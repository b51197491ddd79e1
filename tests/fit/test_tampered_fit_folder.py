"""A fit folder whose files were edited by hand after the fit (fit.json, scenario.toml, lov.csv):
`cistrack export` and `cistrack predict` refuse what no fit writes, naming the file and the field,
with exit status 2: never a traceback, a hang, NaN in an OEM or a predictions CSV, or a time in a
COMMENT that the states contradict. One real fit of the shipped example (C_R A/m estimated, its line
of variations drawn: every part of fit.json an export reads) serves every test; each edits a copy."""
from __future__ import annotations

import dataclasses
import json
import shutil
import warnings
from datetime import timedelta

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.sites import observatory
from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.fitting.from_observations import fit_files
from cistrack.fitting.sky_ephemeris import orbit_of_directory, sky_ephemeris_of
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"


@pytest.fixture(scope="module")
def fit_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("fit") / "fit"
    [one] = fit_files([DATA / "observations.psv"], out=out,
                      settings=["iod.n_particles=1000", "filter.n_particles=1000", "fit.area_to_mass=solve",
                                "fit.lov=3"])
    assert one.ok
    return out


def _copy(fit_dir, tmp_path, edit=None):
    """A copy of the fit folder with ``edit`` (a function of the fit.json dict) applied to fit.json."""
    d = tmp_path / "f"
    shutil.copytree(fit_dir, d)
    if edit is not None:
        rec = json.loads((d / "fit.json").read_text())
        edit(rec)
        (d / "fit.json").write_text(json.dumps(rec))
    return d


def _refused(d, capsys) -> str:
    """The error of export and of predict on ``d`` (the same), once both exited 2 writing nothing."""
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert main(["predict", str(d), "--site", "568", "--quiet"]) == 2
    assert capsys.readouterr().err == err and "Traceback" not in err
    assert not (d / "estimate.oem").exists() and not (d / "sky-568.csv").exists()
    return " ".join(err.split())


def _utc_after(rec: dict, tu: float) -> str:
    return units.format_utc(units.tu_to_utc(units.parse_utc(rec["scenario_epoch_utc"]), tu))


def test_the_fit_as_written_is_exported_and_predicted(fit_dir, tmp_path, capsys):
    d = _copy(fit_dir, tmp_path)
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 0
    assert main(["predict", str(d), "--site", "568", "--quiet"]) == 0


@pytest.mark.parametrize("value", [None, 5, [float("nan")] * 6, [2.0] * 6])
def test_area_to_mass_correlations_that_are_not_six_numbers_from_minus_one_to_one_are_refused(
        fit_dir, tmp_path, capsys, value):
    """A missing one had made export fail with a KeyError; NaN ones had been copied into the OEM's COMMENT."""
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r["area_to_mass"].update(correlations_with_state=value)), capsys)
    assert ("fit.json: field 'area_to_mass.correlations_with_state' must be 6 finite numbers from -1 to 1 "
            "(the correlations with x, y, z, vx, vy, vz)") in err


@pytest.mark.parametrize("field", ["sigma_scaled_m2_kg", "sigma_m2_kg"])
@pytest.mark.parametrize("value", [None, "x", -1.0, float("nan")])
def test_an_area_to_mass_sigma_that_is_not_a_finite_number_at_least_zero_is_refused(
        fit_dir, tmp_path, capsys, field, value):
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r["area_to_mass"].update({field: value})), capsys)
    assert f"fit.json: field 'area_to_mass.{field}' must be a finite number >= 0 (m^2/kg)" in err


def test_an_arc_beginning_decades_before_its_last_observation_is_refused(fit_dir, tmp_path, capsys):
    """first_tu -3000 (36 years back) had made export propagate a 10-minute grid over them: a silent hang."""
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r["arc"].update(first_tu=-3000.0)), capsys)
    assert "fit.json: field 'arc.first_tu' must be the first observation at most 731 days before the last" in err


def test_a_fit_epoch_moved_decades_back_with_its_arc_is_refused(fit_dir, tmp_path, capsys):
    def edit(rec):
        rec["epoch_tu"], rec["epoch_utc"] = -3000.0, _utc_after(rec, -3000.0)
        rec["arc"].update(first_tu=-3001.0, first_utc=_utc_after(rec, -3001.0))
    assert "fit.json: field 'arc.first_tu' must be" in _refused(_copy(fit_dir, tmp_path, edit), capsys)


def test_a_fit_epoch_outside_its_arc_is_refused(fit_dir, tmp_path, capsys):
    def edit(rec):
        rec["epoch_tu"] = rec["arc"]["last_tu"] + 1.0
        rec["epoch_utc"] = _utc_after(rec, rec["epoch_tu"])
    err = _refused(_copy(fit_dir, tmp_path, edit), capsys)
    assert "fit.json: field 'arc' must be first_tu <= epoch_tu" in err and "the fit's epoch is one of its observations" in err


@pytest.mark.parametrize("field", ["first_utc", "last_utc"])
def test_an_arc_time_in_utc_that_its_tu_contradicts_is_refused(fit_dir, tmp_path, capsys, field):
    """The OEM's COMMENT quotes the arc's UTC times: an edited one had been written as the arc."""
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r["arc"].update({field: "2030-01-01T00:00:00Z"})), capsys)
    tu = field.replace("_utc", "_tu")
    assert f"fit.json: field 'arc.{field}' must be a UTC time as text, the scenario's epoch (scenario_epoch_utc) plus arc.{tu}" in err


def test_a_noise_scale_that_makes_the_covariance_infinite_is_refused(fit_dir, tmp_path, capsys):
    """1e300 is positive and finite, but its square is not: the OEM and the predictions had been NaN and inf."""
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r.update(noise_scale=1e300)), capsys)
    assert ("fit.json: field 'noise_scale' must be a positive number (NaN: undefined) small enough that the covariance "
            "scaled by its square (when above 1) keeps its sigmas within 3e+06 km and 100 km/s (got 1e+300)") in err


@pytest.mark.parametrize("value", ["delete", 12345, "garbage"])
def test_a_scenario_epoch_that_is_not_a_utc_time_is_refused(fit_dir, tmp_path, capsys, value):
    """Without it, an edited epoch_utc had gone unchecked into the OEM's COMMENT as the fit epoch."""
    def edit(rec):
        rec.pop("scenario_epoch_utc") if value == "delete" else rec.update(scenario_epoch_utc=value)
        rec["epoch_utc"] = "2030-01-01T00:00:00Z"
    err = _refused(_copy(fit_dir, tmp_path, edit), capsys)
    assert "fit.json: field 'scenario_epoch_utc' must be a UTC time as text (the scenario's epoch" in err


def _burn(rec: dict, t_burn_utc: str | None = None) -> dict:
    """A burn (as a fit writes one) a day after the arc's start, its UTC ``t_burn_utc`` or its own."""
    t_burn_days = float(units.tu_to_days(rec["arc"]["first_tu"])) + 1.0
    return {"t_days": t_burn_days + 0.1, "t_burn_days": t_burn_days, "t_burn_sigma_days": 0.05,
            "t_burn_utc": t_burn_utc or _utc_after(rec, float(units.days_to_tu(t_burn_days))), "delta_v_ms": 0.3,
            "delta_v_sigma_ms": 0.03, "delta_v_vector_ms": [0.3, 0.0, 0.0],
            "delta_v_covariance_ms2": [[9e-4, 0, 0], [0, 9e-4, 0], [0, 0, 9e-4]]}


def test_a_burn_time_in_utc_that_its_days_contradict_is_refused(fit_dir, tmp_path, capsys):
    """The OEM's COMMENT quotes t_burn_utc: 2030 had been written for a burn two days into the arc."""
    err = _refused(_copy(fit_dir, tmp_path, lambda r: r.update(maneuvers=[_burn(r, "2030-01-01T00:00:00Z")])), capsys)
    assert ("fit.json: field 'maneuvers[0].t_burn_utc' must be a UTC time as text, the scenario's epoch "
            "(scenario_epoch_utc) plus t_burn_days") in err and "to within 1 s" in err


def test_a_burn_time_in_utc_that_agrees_with_its_days_is_exported(fit_dir, tmp_path, capsys):
    d = _copy(fit_dir, tmp_path, lambda r: r.update(maneuvers=[_burn(r)]))
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 0
    assert "impulsive burn(s)" in (d / "estimate.oem").read_text()


def test_a_scenario_epoch_that_fit_json_contradicts_is_refused_naming_both_files(fit_dir, tmp_path, capsys):
    """The fit's TU times count from fit.json's scenario_epoch_utc: an edited scenario.toml epoch had
    silently shifted every exported state and prediction by ten days."""
    d = _copy(fit_dir, tmp_path)
    toml = d / "scenario.toml"
    epoch = json.loads((d / "fit.json").read_text())["scenario_epoch_utc"]
    later = units.format_utc(units.parse_utc(epoch) + timedelta(days=10))
    toml.write_text(toml.read_text().replace(f'epoch = "{epoch}"', f'epoch = "{later}"'))
    err = _refused(d, capsys)
    assert (f"scenario.toml: epoch {later} is not the scenario epoch {epoch} of {d / 'fit.json'} "
            "(scenario_epoch_utc), which the fit's times count from") in err


def _with_lov(fit_dir, tmp_path, content: bytes | None):
    """A copy of the fit folder whose lov.csv holds ``content`` (None: no lov.csv)."""
    d = _copy(fit_dir, tmp_path)
    if content is None:
        (d / "lov.csv").unlink()
    else:
        (d / "lov.csv").write_bytes(content)
    return d


def _lov_edited(fit_dir, row: int, column: str, value: str) -> bytes:
    lines = (fit_dir / "lov.csv").read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = value
    lines[row] = ",".join(cells)
    return ("\n".join(lines) + "\n").encode()


@pytest.mark.parametrize("damage, told", [
    (lambda f: _lov_edited(f, 3, "x_km", "nan"), "line 4, column x_km: 'nan' is not a finite number"),
    (lambda f: _lov_edited(f, 3, "chi2", "abc"), "line 4, column chi2: 'abc' is not a number"),
    (lambda f: _lov_edited(f, 3, "x_km", "1e300"), "holds a state no orbit of the fit's has (beyond 3e+06 km or 100 km/s)"),
    (lambda f: (f / "lov.csv").read_bytes().splitlines(keepends=True)[0], "holds no point of the line (its header only)"),
    (lambda f: b"sigma,chi2,x_km\n0.0,1.0,2.0\n", "has no column 'y_km'"),
    (lambda f: b"\xff\xfe\x00garbage", "cannot be read"),
])
def test_a_damaged_line_of_variations_is_ignored_with_a_warning_naming_lov_csv(fit_dir, tmp_path, damage, told):
    """As a missing lov.csv, it is not used (the linear covariance), but not silently: a NaN or text cell,
    a missing column or garbage had been dropped without a word, and 1e300 had printed numpy's
    'overflow encountered in multiply'."""
    without = _with_lov(fit_dir, tmp_path / "a", None)
    assert _warned(["predict", str(without), "--site", "568", "--quiet"]) == []
    d = _with_lov(fit_dir, tmp_path / "b", damage(fit_dir))
    for argv in (["predict", str(d), "--site", "568", "--quiet"], ["export", str(d), "--format", "oem", "--quiet"]):
        [warned] = _warned(argv)   # that one only: no numpy warning
        assert warned.startswith(f"{d / 'lov.csv'}: {told}") and "the line of variations is ignored" in warned
    assert (d / "sky-568.csv").read_bytes() == (without / "sky-568.csv").read_bytes()


def _warned(argv: list[str]) -> list[str]:
    """The warnings (every kind) of the command ``argv``, once it exited 0."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(argv) == 0
    return [str(w.message) for w in caught]


def test_sky_predictions_holding_a_value_that_is_not_finite_are_not_written(fit_dir, tmp_path):
    """The last guard behind fit.json's checks: a NaN or infinite ellipse is refused, never written as 'nan'."""
    orbit = orbit_of_directory(fit_dir)
    sky = sky_ephemeris_of(orbit, orbit.t0 + np.linspace(0.0, 0.2, 3), observatory("568"))
    cov = sky.covariance_arcsec2.copy()
    cov[1] = np.inf
    with pytest.raises(ConfigError, match=r"the sky predictions: 1 of 3 times hold a value that is not a finite number "
                                          r"\(NaN or infinite\), the first at .*; nothing was written"):
        dataclasses.replace(sky, covariance_arcsec2=cov).write_csv(tmp_path / "sky.csv")
    assert not (tmp_path / "sky.csv").exists()
    assert sky.write_csv(tmp_path / "sky.csv").is_file()


def test_states_or_covariances_to_export_that_are_not_finite_are_refused_naming_the_first_time():
    from cistrack.fitting.fit_export import refuse_non_finite   # export_fit's last guard behind fit.json's checks

    values = np.ones((3, 42))
    values[2, 40] = np.nan
    with pytest.raises(ConfigError, match=r"FIT: 1 of 3 times hold a value that is not a finite number \(NaN or "
                                          r"infinite\), the first at 2026-03-02T00:20:00Z; nothing was written"):
        refuse_non_finite(values, ["2026-03-02T00:00:00Z", "2026-03-02T00:10:00Z", "2026-03-02T00:20:00Z"], "FIT")


def _moved_to_2061(rec: dict) -> None:
    """The fit's epoch moved 36 years on (2061, beyond DE421), its arc and UTC times with it."""
    rec["epoch_tu"], rec["epoch_utc"] = 3000.0, _utc_after(rec, 3000.0)
    rec["arc"].update(first_tu=2999.0, last_tu=3000.0, first_utc=_utc_after(rec, 2999.0), last_utc=_utc_after(rec, 3000.0))


def test_a_fit_epoch_beyond_the_ephemeris_is_blamed_on_fit_json_not_on_an_option_not_given(fit_dir, tmp_path, capsys):
    """Moved 36 years on (2061, its arc and UTC times with it), the default --start had been blamed."""
    d = _copy(fit_dir, tmp_path, _moved_to_2061)
    assert main(["predict", str(d), "--site", "568", "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert (f"{d}: the orbit's epoch (fit.json epoch_utc, the default --start) 2061-" in err
            and "sky predictions need the DE421 ephemeris" in err and "--start 2061" not in err)


def test_a_fit_epoch_beyond_the_ephemeris_is_not_exported_in_the_frame_placed_by_it(fit_dir, tmp_path, capsys):
    """The OEM's GCRF states come from the real Earth-Moon frame, placed by DE421's Moon at each time:
    a 2061 fit had been exported (exit 0) with the Moon read beyond the years cistrack takes from DE421."""
    d = _copy(fit_dir, tmp_path, _moved_to_2061)
    assert main(["export", str(d), "--format", "oem", "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert (f"{d}: the orbit's epoch (fit.json epoch_utc) 2061-" in err and "from the real Earth-Moon rotating frame "
            "(DE421)), which covers the years 1900 to 2052" in err and not (d / "estimate.oem").exists())
