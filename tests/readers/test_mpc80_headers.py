"""MPC 80-column files as submitted to the MPC: the header lines (COD, OBS, MEA, TEL, NET, ACK,
AC2, CON, COM, BND, NUM) carry no observation and are skipped, and spaces after column 80 (a
line copied from a web page) are read past (both had been refused as lines of the wrong length)."""
from __future__ import annotations

import pytest

from cistrack.runs.observation_files import read_observations

EPOCH = "2026-03-01T00:00:00Z"
LINE = "     K26A01A  C2026 03 01.04167606 51 33.239-07 54 18.29                     809"
HEADER = ["COD 809", "CON A. Observer, 1 Main Street", "OBS J. Smith", "MEA J. Smith", "TEL 1.0-m f/8 reflector + CCD",
          "NET Gaia-DR3", "BND G", "COM Long exposures", "NUM 2", "ACK batch 1", "AC2 observer@example.com"]


def _read(tmp_path, text: str):
    path = tmp_path / "submission.obs"
    path.write_text(text)
    return read_observations(path, EPOCH)


@pytest.mark.parametrize("header", HEADER, ids=[h[:3] for h in HEADER])
def test_a_submission_header_line_is_skipped(tmp_path, header):
    assert len(_read(tmp_path, f"{header}\n{LINE}\n")) == 1


def test_a_whole_submission_header_is_skipped(tmp_path):
    ms = _read(tmp_path, "\n".join(HEADER + [LINE, LINE.replace("01.041676", "01.083333")]) + "\n")
    assert ms.sites.tolist() == ["809", "809"]


@pytest.mark.parametrize("tail", ["   ", " \t "], ids=["spaces", "spaces and a tab"])
def test_spaces_after_column_80_are_read_past(tmp_path, tail):
    assert len(_read(tmp_path, LINE + tail + "\n")) == 1
