"""Hostile inputs to `cistrack fit`: the same observations in two formats, TDM angles written in
radians, an az/el CSV without sites, and files larger than the stated limit."""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError, MeasurementError
from cistrack.fitting.observation_input import MAX_FILE_MB, MAX_FILE_MB_ENV, read_object_observations
from cistrack.plugin.registry import default_registry
from cistrack.runs.observation_files import read_observations, write_observations
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
EPOCH = "2026-03-01T00:00:00Z"


def _as_mpc80(tmp_path, shift_arcsec: float = 0.0):
    """The shipped ADES observations written again as MPC 80-column (times to 1e-6 day), the
    declinations moved by ``shift_arcsec``."""
    ms = read_observations(DATA / "observations.psv", EPOCH)
    ms.values[:, 1] += shift_arcsec * math.pi / 648_000
    path = tmp_path / "observations.obs"
    write_observations(path, ms, EPOCH, format="mpc80")
    return path


def _in_radians(tmp_path):
    """The shipped TDM with every angle value written in radians."""
    text = (DATA / "observations.tdm").read_text()
    path = tmp_path / "radians.tdm"
    path.write_text(re.sub(r"^(ANGLE_[12] = \S+ )(\S+)$", lambda m: f"{m[1]}{math.radians(float(m[2]))!r}", text,
                           flags=re.M))
    return path


# -- the same observations given twice ------------------------------------------------------------

def test_observations_given_as_ades_and_as_mpc_80_column_are_used_once(tmp_path):
    objs = read_object_observations([DATA / "observations.psv", _as_mpc80(tmp_path)], default_registry())
    assert len(objs[0].measurements) == 65


def test_the_dropped_duplicates_are_counted_naming_both_files(tmp_path):
    objs = read_object_observations([DATA / "observations.psv", _as_mpc80(tmp_path)], default_registry())
    assert "observations.obs: 65 observations dropped as duplicates of those in observations.psv" in objs[0].notes[-1]
    assert objs[0].measurements.meta["duplicates_dropped"] == 65


def test_the_copy_kept_is_the_one_with_the_finer_times_whichever_file_comes_first(tmp_path):
    objs = read_object_observations([_as_mpc80(tmp_path), DATA / "observations.psv"], default_registry())
    ades = read_object_observations([DATA / "observations.psv"], default_registry())[0].measurements
    np.testing.assert_array_equal(objs[0].measurements.times, ades.times)
    np.testing.assert_array_equal(objs[0].measurements.values, ades.values)


def test_two_files_at_one_site_and_time_with_positions_far_apart_are_refused_naming_both(tmp_path):
    with pytest.raises(MeasurementError, match=r"observations\.psv and .*observations\.obs .*30(\.0)? arcsec apart"):
        read_object_observations([DATA / "observations.psv", _as_mpc80(tmp_path, shift_arcsec=30.0)],
                                 default_registry())


# -- TDM angles in radians -------------------------------------------------------------------------

def test_a_tdm_whose_angles_are_radians_is_refused_naming_the_file_and_the_keywords(tmp_path):
    with pytest.raises(MeasurementError, match=r"radians\.tdm.*ANGLE_1/ANGLE_2.*look like radians.*degrees"):
        read_observations(_in_radians(tmp_path), EPOCH)


def test_fit_says_so_under_quiet_and_exits_with_an_input_error(tmp_path, capsys):
    assert main(["fit", str(_in_radians(tmp_path)), "--out", str(tmp_path / "fit"), "--quiet"]) == 2
    assert "look like radians" in capsys.readouterr().err
    assert not (tmp_path / "fit").exists()


def test_check_degrees_false_reads_such_a_file_as_degrees(tmp_path):
    ms = read_observations(_in_radians(tmp_path), EPOCH, check_degrees=False)
    assert len(ms) == 65 and float(np.max(ms.values[:, 0])) < math.radians(2 * math.pi)


def _ades_in_radians(tmp_path, fmt: str):
    """The shipped ADES observations with every ra and dec written in radians, as ``fmt`` (ades-psv, ades-xml)."""
    ms = read_observations(DATA / "observations.psv", EPOCH)
    ms.values[:, :2] = np.radians(ms.values[:, :2])
    path = tmp_path / f"radians.{fmt.split('-')[1]}"
    write_observations(path, ms, EPOCH, format=fmt)
    return path


@pytest.mark.parametrize("fmt", ["ades-psv", "ades-xml"])
def test_an_ades_file_whose_angles_are_radians_is_refused_as_the_tdm_one_is(tmp_path, fmt):
    """Probe L8: such a file had been read without a word and its fit's misfit blamed on a maneuver."""
    path = _ades_in_radians(tmp_path, fmt)
    with pytest.raises(MeasurementError, match=rf"{re.escape(path.name)}, line \d+, field ra/dec values: all 65 "
                                               r"observations have ra within \[0, 6\.2832\] and dec within "
                                               rf"\[-1\.5708, 1\.5708\]: these look like radians, but ADES angles "
                                               rf"are degrees; .* the {fmt} reader's check_degrees = false"):
        read_observations(path, EPOCH)


def test_check_degrees_false_reads_such_an_ades_file_as_degrees(tmp_path):
    ms = read_observations(_ades_in_radians(tmp_path, "ades-psv"), EPOCH, check_degrees=False)
    assert len(ms) == 65 and float(np.max(ms.values[:, 0])) < math.radians(2 * math.pi)


def _one_site_in_radians(tmp_path, site: str = "711"):
    """The shipped ADES observations (711 and 809) with ``site``'s ra and dec written in radians."""
    ms = read_observations(DATA / "observations.psv", EPOCH)
    mine = np.asarray(ms.sites) == site
    ms.values[mine, :2] = np.radians(ms.values[mine, :2])
    path = tmp_path / "one_site_radians.psv"
    write_observations(path, ms, EPOCH, format="ades-psv")
    return path


def test_a_file_whose_one_site_is_in_radians_is_refused_naming_the_site_and_the_way_out(tmp_path):
    """Probe M8: 568's rows in radians beside Q62's in degrees had been fitted, the misfit blamed on a maneuver."""
    with pytest.raises(MeasurementError, match=r"one_site_radians\.psv, line \d+, field ra/dec values: all 33 "
                                               r"observations of site 711 have ra within \[0, 6\.2832\] .*while the "
                                               r"other sites' do not: these look like radians.*check_degrees = false"):
        read_observations(_one_site_in_radians(tmp_path), EPOCH)


def test_one_site_seeing_a_real_object_near_ra_3_deg_and_the_equator_is_read_as_degrees(tmp_path):
    """711's first four rows moved to RA 1.8-3.0 deg, Dec 0.5-0.9 deg (the radians box) with 809's
    rows moved alike: read as radians they would lie 30-50 deg from 809's, as written 1-2 deg."""
    ms = read_observations(DATA / "observations.psv", EPOCH)
    sites = np.asarray(ms.sites)
    keep = np.flatnonzero(sites == "809").tolist() + np.flatnonzero(sites == "711")[:4].tolist()
    ms = ms.subset(np.sort(np.asarray(keep)))
    ms.values[:, 0] -= math.radians(139.5)
    ms.values[:, 1] -= math.radians(6.0)
    path = tmp_path / "near_ra_zero.psv"
    write_observations(path, ms, EPOCH, format="ades-psv")
    read = read_observations(path, EPOCH)
    assert int(np.sum(np.asarray(read.sites) == "711")) == 4


def test_check_degrees_false_reads_a_file_with_one_site_in_radians_as_written(tmp_path):
    ms = read_observations(_one_site_in_radians(tmp_path), EPOCH, check_degrees=False)
    assert int(np.sum(ms.values[:, 0] < math.radians(2 * math.pi))) == 33


# -- an az/el CSV without sites ----------------------------------------------------------------------

def test_an_azel_csv_without_a_site_column_is_refused_naming_the_file_and_the_column(tmp_path, capsys):
    p = tmp_path / "azel.csv"
    p.write_text("time_utc,azimuth_deg,elevation_deg\n2026-03-01T22:35:00Z,120.5,40.2\n"
                 "2026-03-01T22:45:00Z,120.7,40.5\n")
    assert main(["fit", str(p), "--out", str(tmp_path / "fit"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "azel.csv: no column 'site'" in err and "MPC observatory code" in err
    assert "tdm" not in err.lower()


# -- the file-size limit -----------------------------------------------------------------------------

def test_the_default_limit_is_generous_for_survey_files():
    assert MAX_FILE_MB == 50.0


def test_a_file_over_the_limit_is_refused_before_reading_naming_its_size_and_how_to_raise_it(tmp_path,
                                                                                             monkeypatch):
    monkeypatch.setenv(MAX_FILE_MB_ENV, "0.001")
    p = tmp_path / "big.psv"
    p.write_bytes(b"x" * 2000)  # not even an observation file: it is never read
    with pytest.raises(ConfigError, match=r"big\.psv: 2,000 bytes \(0\.002 MB\) is larger than the 0\.001 MB limit.*"
                                          r"--max-file-mb.*CISTRACK_MAX_FILE_MB"):
        read_object_observations([p], default_registry())


def test_max_file_mb_sets_the_limit_of_cistrack_fit(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv(MAX_FILE_MB_ENV, raising=False)
    p = tmp_path / "obs.psv"
    p.write_text((DATA / "observations.psv").read_text())
    assert main(["fit", str(p), "--out", str(tmp_path / "fit"), "--quiet", "--max-file-mb", "0.001"]) == 2
    assert "0.001 MB limit" in capsys.readouterr().err


def test_a_file_just_over_the_limit_shows_a_size_that_differs_from_it(tmp_path, monkeypatch):
    monkeypatch.setenv(MAX_FILE_MB_ENV, "0.002")
    p = tmp_path / "big.psv"
    p.write_bytes(b"x" * 2001)
    with pytest.raises(ConfigError, match=r"big\.psv: 2,001 bytes \(0\.002001 MB\) is larger than the 0\.002 MB"):
        read_object_observations([p], default_registry())


def test_a_limit_that_is_not_a_positive_number_is_refused_naming_the_variable(tmp_path, monkeypatch):
    monkeypatch.setenv(MAX_FILE_MB_ENV, "lots")
    with pytest.raises(ConfigError, match="CISTRACK_MAX_FILE_MB='lots': must be a finite, positive number"):
        read_object_observations([DATA / "observations.psv"], default_registry())


def test_an_infinite_limit_is_refused_as_not_finite(tmp_path, monkeypatch, capsys):
    """inf had been refused as if it were not positive ("give a number of MB > 0")."""
    monkeypatch.setenv(MAX_FILE_MB_ENV, "inf")
    with pytest.raises(ConfigError, match="CISTRACK_MAX_FILE_MB='inf': must be a finite, positive number of MB"):
        read_object_observations([DATA / "observations.psv"], default_registry())
    monkeypatch.delenv(MAX_FILE_MB_ENV)
    with pytest.raises(SystemExit):
        main(["fit", str(DATA / "observations.psv"), "--out", str(tmp_path / "fit"), "--max-file-mb", "inf"])
    assert "'inf': give a finite number of MB > 0" in capsys.readouterr().err


# -- check_degrees = false in cistrack fit --------------------------------------------------------------

NEAR_RA_ZERO = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
nrho|CCD|568|2026-04-29T07:30:14.099192Z|3.057058210979619|0.6083358575476927|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T07:42:20.275941Z|3.127461060279586|0.5594089501353201|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T07:55:00.136433Z|3.2006285995154826|0.5076495985767702|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:26:49.246598Z|4.365858469207637|-0.37467453386028193|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:34:22.810826Z|4.410507285833944|-0.4067805283884791|0.706|0.706|Gaia3
nrho|CCD|568|2026-04-29T11:42:27.313984Z|4.531327386127089|-0.4595938930986243|0.706|0.706|Gaia3
"""


def test_fit_with_check_degrees_false_fits_observations_near_ra_zero(tmp_path, capsys):
    """The way out the radians refusal names: the fit's own copy of such observations had been
    refused by the run that reads it, so that check_degrees = false never reached a least squares."""
    (tmp_path / "near0.psv").write_text(NEAR_RA_ZERO)
    main(["fit", str(tmp_path / "near0.psv"), "--out", str(tmp_path / "fit"),
          "--set", "measurements.reader.check_degrees=false"])
    assert "look like radians" not in capsys.readouterr().out
    assert json.loads((tmp_path / "fit" / "fit.json").read_text())["n_used"] == 6
