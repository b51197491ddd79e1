"""TDM segments without PARTICIPANT_2 (the object): beside segments of one object they are that
object's; beside segments of several objects they are refused, naming the file, the line and how
many observations name no object, never left out."""
from __future__ import annotations

import re

import pytest

from cistrack.errors import MeasurementError
from cistrack.fitting.observation_input import read_object_observations
from cistrack.plugin.registry import default_registry
from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
HEAD = "CCSDS_TDM_VERS = 2.0\nCREATION_DATE = 2026-03-01T00:00:00\nORIGINATOR = cistrack\n"


def _segment(obj: str | None, hour: int) -> str:
    named = f"PARTICIPANT_2 = {obj}\n" if obj else ""
    return (f"META_START\nTIME_SYSTEM = UTC\nPARTICIPANT_1 = 705\n{named}ANGLE_TYPE = AZEL\nMETA_STOP\nDATA_START\n"
            f"ANGLE_1 = 2026-03-01T0{hour}:00:00 10.5\nANGLE_2 = 2026-03-01T0{hour}:00:00 20.5\n"
            f"ANGLE_1 = 2026-03-01T0{hour}:30:00 10.6\nANGLE_2 = 2026-03-01T0{hour}:30:00 20.6\nDATA_STOP\n")


def _tdm(tmp_path, *objects: str | None):
    path = tmp_path / "objects.tdm"
    path.write_text(HEAD + "".join(_segment(obj, hour) for hour, obj in enumerate(objects, start=1)))
    return path


def test_unnamed_segments_beside_two_objects_are_refused_naming_the_file_line_and_count(tmp_path):
    path = _tdm(tmp_path, "A", "B", None)
    with pytest.raises(MeasurementError, match=rf"{re.escape(str(path))}, line 34, field \(object\): 2 of the file's 6 observations "
                                               r"\(the first on this line\) name no object, beside observations of 2 "
                                               r"objects \('A', 'B'\)"):
        read_object_observations([path], default_registry())


def test_they_are_refused_also_when_one_object_is_asked_for(tmp_path):
    with pytest.raises(MeasurementError, match="2 of the file's 6 observations"):
        read_observations(_tdm(tmp_path, "A", "B", None), EPOCH, designation="A")


def test_unnamed_segments_beside_one_object_are_that_objects_when_it_is_asked_for(tmp_path):
    ms = read_observations(_tdm(tmp_path, "A", None), EPOCH, designation="A")
    assert len(ms) == 4 and ms.meta["object"] == "A"
