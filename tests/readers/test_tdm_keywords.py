"""TDM metadata keywords that change what the data mean: DATA_QUALITY, TIMETAG_REF and the
integration interval (CCSDS 503.0-B-2), read on the shipped example with one keyword added to
every segment."""
from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest

from cistrack.errors import MeasurementError
from cistrack.runs.observation_files import read_observations
from cistrack.scenario.loading import builtin_scenario_path
from cistrack.units import TU_S

TDM = builtin_scenario_path("real-data").parent / "real_data" / "observations.tdm"
EPOCH = "2026-03-01T00:00:00Z"


def _with_meta(tmp_path, *lines: str, segments: int | None = None):
    """The shipped TDM with ``lines`` added before META_STOP of its first ``segments`` segments (all: None)."""
    parts = TDM.read_text().split("META_STOP")
    n = len(parts) - 1 if segments is None else segments
    text = "".join(p + ("\n".join(lines) + "\nMETA_STOP" if i < n else "META_STOP")
                   for i, p in enumerate(parts[:-1])) + parts[-1]
    path = tmp_path / "keywords.tdm"
    path.write_text(text)
    return path


# -- DATA_QUALITY -------------------------------------------------------------------------------------

@pytest.mark.parametrize("quality", ["RAW", "VALIDATED"])
def test_raw_and_validated_data_are_read_as_they_are(tmp_path, quality, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_with_meta(tmp_path, f"DATA_QUALITY = {quality}"), EPOCH)
    assert len(ms) == 65 and "DEGRADED" not in caplog.text


def test_rejected_data_are_refused_naming_the_file_the_keyword_and_its_value(tmp_path):
    with pytest.raises(MeasurementError, match=r"keywords\.tdm, line 14, field DATA_QUALITY: 'REJECTED': the data "
                                               r"of the segment starting at line 5 are not to be used; RAW and "
                                               r"VALIDATED data are read, DEGRADED with a warning"):
        read_observations(_with_meta(tmp_path, "DATA_QUALITY = REJECTED", segments=1), EPOCH)


def test_degraded_data_are_used_with_a_warning_naming_the_file(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(_with_meta(tmp_path, "DATA_QUALITY = DEGRADED", segments=1), EPOCH)
    assert len(ms) == 65
    assert "keywords.tdm: 3 observations (from line 18) are in segments with DATA_QUALITY = DEGRADED" in caplog.text


# -- TIMETAG_REF ----------------------------------------------------------------------------------------

def test_a_receive_time_tag_is_what_angles_have(tmp_path):
    assert len(read_observations(_with_meta(tmp_path, "TIMETAG_REF = RECEIVE"), EPOCH)) == 65


def test_a_transmit_time_tag_is_refused_naming_the_keyword(tmp_path):
    with pytest.raises(MeasurementError, match=r"keywords\.tdm, line 14, field TIMETAG_REF: 'TRANSMIT': optical "
                                               r"angles are tagged with the time the light was received"):
        read_observations(_with_meta(tmp_path, "TIMETAG_REF = TRANSMIT"), EPOCH)


# -- INTEGRATION_INTERVAL and INTEGRATION_REF ------------------------------------------------------------------

def _seconds_moved(tmp_path, *lines: str) -> np.ndarray:
    plain = read_observations(TDM, EPOCH)
    moved = read_observations(_with_meta(tmp_path, *lines), EPOCH)
    np.testing.assert_array_equal(moved.values, plain.values)
    return (moved.times - plain.times) * TU_S


@pytest.mark.parametrize("ref, seconds", [("START", 5.0), ("END", -5.0), ("MIDDLE", 0.0)])
def test_a_time_tag_at_the_start_or_end_of_the_exposure_is_moved_to_its_middle(tmp_path, ref, seconds):
    moved = _seconds_moved(tmp_path, "INTEGRATION_INTERVAL = 10", f"INTEGRATION_REF = {ref}")
    np.testing.assert_allclose(moved, seconds, atol=1e-6)


def test_an_interval_without_a_reference_is_taken_at_the_middle(tmp_path):
    np.testing.assert_allclose(_seconds_moved(tmp_path, "INTEGRATION_INTERVAL = 30"), 0.0, atol=1e-6)


def test_the_move_is_half_the_interval_to_the_microsecond(tmp_path):
    ms = read_observations(_with_meta(tmp_path, "INTEGRATION_INTERVAL = 0.000004", "INTEGRATION_REF = START"), EPOCH)
    assert timedelta(seconds=float(ms.times[0]) * TU_S) - timedelta(hours=22, minutes=35) == timedelta(microseconds=2)


def test_a_start_reference_without_an_interval_is_refused(tmp_path):
    with pytest.raises(MeasurementError, match=r"field INTEGRATION_REF: START needs INTEGRATION_INTERVAL"):
        read_observations(_with_meta(tmp_path, "INTEGRATION_REF = START"), EPOCH)


@pytest.mark.parametrize("value", ["0", "-4", "nan", "1e9", "ten"])
def test_an_interval_that_is_no_exposure_is_refused_naming_what_is_allowed(tmp_path, value):
    with pytest.raises(MeasurementError, match=r"field INTEGRATION_INTERVAL: .*a number of seconds in \(0, 86400\]"):
        read_observations(_with_meta(tmp_path, f"INTEGRATION_INTERVAL = {value}", "INTEGRATION_REF = END"), EPOCH)


def test_an_unknown_reference_is_refused_naming_the_three_allowed(tmp_path):
    with pytest.raises(MeasurementError, match=r"field INTEGRATION_REF: 'CENTRE': START, MIDDLE or END"):
        read_observations(_with_meta(tmp_path, "INTEGRATION_INTERVAL = 10", "INTEGRATION_REF = CENTRE"), EPOCH)
