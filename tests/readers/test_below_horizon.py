"""Az/el observations far below a ground site's horizon, where no telescope sees anything, are
used as given with a warning naming the file, the first such line and how many (they had been
read without a word, and the fit then failed with nothing pointing at the angles); a TDM's
REFERENCE_FRAME beside AZEL angles, which it does not apply to, is said too."""
from __future__ import annotations

from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
TDM_HEAD = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"


def _csv(tmp_path, elevations):
    path = tmp_path / "azel.csv"
    rows = "".join(f"2026-03-01T0{k + 1}:00:00Z,100.0,{e}\n" for k, e in enumerate(elevations))
    path.write_text("time_utc,azimuth_deg,elevation_deg\n" + rows)
    return path


def _tdm(tmp_path, elevations, frame=""):
    seg = ("META_START\nTIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\nPARTICIPANT_2 = X\nANGLE_TYPE = AZEL\n"
           f"{frame}META_STOP\nDATA_START\n")
    seg += "".join(f"ANGLE_1 = 2026-03-01T0{k + 1}:00:00 100.0\nANGLE_2 = 2026-03-01T0{k + 1}:00:00 {e}\n"
                   for k, e in enumerate(elevations))
    path = tmp_path / "azel.tdm"
    path.write_text(TDM_HEAD + seg + "DATA_STOP\n")
    return path


def test_a_csv_with_elevations_far_below_the_horizon_is_read_with_a_warning_naming_the_first_line(tmp_path, caplog):
    path = _csv(tmp_path, [30.0, -30.0, -80.0])
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        ms = read_observations(path, EPOCH)
    assert len(ms) == 3
    assert f"{path}, line 3: 2 of 3 elevations lie more than 5 degrees below the horizon (this one -30 deg)" \
        in caplog.text, caplog.text


def test_a_tdm_with_elevations_far_below_the_horizon_is_read_with_a_warning(tmp_path, caplog):
    path = _tdm(tmp_path, [-40.0, 20.0])
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(path, EPOCH)
    assert "1 of 2 elevations lie more than 5 degrees below the horizon (this one -40 deg)" in caplog.text, caplog.text


def test_elevations_at_or_a_little_under_the_horizon_are_read_without_a_word(tmp_path, caplog):
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(_csv(tmp_path, [0.0, -2.0, 10.0]), EPOCH)
    assert "horizon" not in caplog.text


def test_a_reference_frame_beside_azel_angles_is_said_not_to_apply(tmp_path, caplog):
    path = _tdm(tmp_path, [20.0, 21.0], frame="REFERENCE_FRAME = ICRF\n")
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(path, EPOCH)
    assert f"{path}, line 9: REFERENCE_FRAME = 'ICRF' applies to RADEC angles" in caplog.text, caplog.text


def test_a_reference_frame_in_many_azel_segments_is_said_once(tmp_path, caplog):
    path = _tdm(tmp_path, [20.0, 21.0], frame="REFERENCE_FRAME = ICRF\n")
    one = path.read_text()
    head, seg = one[:len(TDM_HEAD)], one[len(TDM_HEAD):]
    path.write_text(head + seg + seg.replace("T01:", "T03:").replace("T02:", "T04:"))
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        read_observations(path, EPOCH)
    assert caplog.text.count("applies to RADEC angles") == 1 and "(and in 1 more AZEL segment(s))" in caplog.text
