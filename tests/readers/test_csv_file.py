"""Measurement CSV: round trip with simulated data, defaults, and line-numbered errors."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import MeasurementError
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.plugins.readers.csv_file import read_measurements, write_measurements
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S

EPOCH = "2026-01-01T00:00:00Z"
HEADER = "time_utc,azimuth_deg,elevation_deg\n"


def write(tmp_path, text, name="obs.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("measure_range", [False, True])
def test_simulated_measurements_survive_a_write_read_round_trip(tmp_path, nrho_arc, measure_range):
    times, states = nrho_arc
    s = GroundTelescope(measure_range=measure_range)
    ms = s.simulate(states[::7], times[::7], np.random.default_rng(0))
    p = tmp_path / "sim.csv"
    write_measurements(p, ms, EPOCH)
    back = read_measurements(p, EPOCH)
    assert back.names == ms.names
    assert np.allclose(back.times, ms.times, atol=1e-6 / TU_S)          # microsecond times
    assert np.allclose(back.values, ms.values, rtol=1e-13, atol=1e-15)
    assert np.allclose(back.sigmas, ms.sigmas, rtol=1e-13)


def test_times_are_counted_from_the_given_epoch(tmp_path):
    p = write(tmp_path, HEADER + "2026-01-02T00:00:00Z,10,20\n")
    ms = read_measurements(p, EPOCH)
    assert np.isclose(ms.times[0], 86400.0 / TU_S)
    assert np.allclose(ms.values[0], np.radians([10.0, 20.0]))


def test_missing_sigma_columns_take_the_defaults(tmp_path):
    p = write(tmp_path, "time_utc,azimuth_deg,elevation_deg,range_km\n"
                        "2026-01-01T01:00:00Z,10,20,400000\n")
    ms = read_measurements(p, EPOCH, sigma_arcsec=2.0, range_alpha=0.1)
    assert np.allclose(ms.sigmas[0], [2 * ARCSEC_RAD, 2 * ARCSEC_RAD, 40000.0 / LU_KM])


def test_per_row_sigmas_are_read_and_empty_cells_fall_back(tmp_path):
    p = write(tmp_path, "time_utc,azimuth_deg,elevation_deg,sigma_azimuth_arcsec,sigma_elevation_arcsec\n"
                        "2026-01-01T01:00:00Z,10,20,3.0,\n")
    ms = read_measurements(p, EPOCH)
    assert np.allclose(ms.sigmas[0] / ARCSEC_RAD, [3.0, 1.5])


def test_comments_blank_lines_and_column_order_are_free(tmp_path):
    p = write(tmp_path, "# observatory: test\n\nelevation_deg,time_utc,azimuth_deg\n"
                        "# a comment between rows\n20,2026-01-01T01:00:00Z,359.5\n")
    ms = read_measurements(p, EPOCH)
    assert np.allclose(ms.values[0], np.radians([359.5, 20.0]))


def test_range_can_be_left_out_for_angles_only_od(tmp_path):
    p = write(tmp_path, "time_utc,azimuth_deg,elevation_deg,range_km\n2026-01-01T01:00:00Z,10,20,4e5\n")
    assert read_measurements(p, EPOCH, include_range=False).names == ("azimuth", "elevation")


@pytest.mark.parametrize("row, words", [
    ("not-a-time,10,20", "time_utc"),
    ("2026-01-01T01:00:00Z,360,20", "azimuth_deg"),
    ("2026-01-01T01:00:00Z,-1,20", "azimuth_deg"),
    ("2026-01-01T01:00:00Z,10,91", "elevation_deg"),
    ("2026-01-01T01:00:00Z,nan,20", "azimuth_deg"),
    ("2026-01-01T01:00:00Z,10,", "elevation_deg"),
    ("2026-01-01T01:00:00Z,10", "fields"),
])
def test_an_invalid_row_is_reported_with_file_and_line_number(tmp_path, row, words):
    p = write(tmp_path, "# comment\n" + HEADER + "2026-01-01T00:30:00Z,10,20\n" + row + "\n")
    with pytest.raises(MeasurementError) as exc:
        read_measurements(p, EPOCH)
    msg = str(exc.value)
    assert str(p) in msg and "line 4" in msg and words in msg


def test_times_that_do_not_increase_are_reported(tmp_path):
    p = write(tmp_path, HEADER + "2026-01-01T02:00:00Z,10,20\n2026-01-01T01:00:00Z,10,20\n")
    with pytest.raises(MeasurementError, match="line 3.*not after line 2"):
        read_measurements(p, EPOCH)


def test_every_invalid_row_is_reported_not_just_the_first(tmp_path):
    p = write(tmp_path, HEADER + "x,10,20\n2026-01-01T01:00:00Z,10,20\n2026-01-01T02:00:00Z,400,20\n")
    with pytest.raises(MeasurementError) as exc:
        read_measurements(p, EPOCH)
    assert "2 invalid row(s)" in str(exc.value)
    assert "line 2" in str(exc.value) and "line 4" in str(exc.value)


@pytest.mark.parametrize("header", ["time_utc,azimuth_deg\n", "time_utc,azimuth_deg,elevation_deg,mag\n",
                                    "time_utc,azimuth_deg,elevation_deg,sigma_range_km\n"])
def test_a_bad_header_is_reported(tmp_path, header):
    p = write(tmp_path, header + "2026-01-01T01:00:00Z,10,20,1\n")
    with pytest.raises(MeasurementError, match="line 1"):
        read_measurements(p, EPOCH)


def test_a_missing_file_raises_measurement_error(tmp_path):
    with pytest.raises(MeasurementError, match="cannot read"):
        read_measurements(tmp_path / "none.csv", EPOCH)


def test_a_file_without_rows_raises_measurement_error(tmp_path):
    with pytest.raises(MeasurementError, match="no measurements"):
        read_measurements(write(tmp_path, HEADER), EPOCH)
