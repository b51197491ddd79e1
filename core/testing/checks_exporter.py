"""Conformance checks for Exporter plugins: they write a file naming the frame, and refuse an
empty estimate with a CistrackError."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from cistrack.errors import CistrackError
from cistrack.results.inertial_frame import InertialEstimates, InertialFrame
from cistrack.interfaces.exporter import Exporter
from cistrack.testing.check_support import require

__all__ = ["EXPORTER_CHECKS", "sample_inertial_estimates"]


def sample_inertial_estimates(k: int = 4) -> InertialEstimates:
    """``k`` hourly states of a 400,000 km circular-ish orbit with 1 km / 1 m/s covariances."""
    frame = InertialFrame("ICRF", "test frame", lambda x, t: x, ccsds=True)
    t = np.arange(k) * 3600.0 / 375_149.0
    ang = np.arange(k) * 1e-3
    states = np.column_stack([4e5 * np.cos(ang), 4e5 * np.sin(ang), np.zeros(k), -np.sin(ang), np.cos(ang), np.zeros(k)])
    cov = np.broadcast_to(np.diag([1.0, 1.0, 1.0, 1e-6, 1e-6, 1e-6]), (k, 6, 6)).copy()
    utc = np.array([f"2026-03-01T{h:02d}:00:00.000000Z" for h in range(k)])
    return InertialEstimates(frame, utc, t, states, cov, np.arange(k), np.full(k, "update"))


def check_is_exporter(exporter) -> None:
    require(isinstance(exporter, Exporter), f"{type(exporter).__name__} does not derive from cistrack.interfaces.Exporter")


def check_writes_a_file_naming_the_frame(exporter) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / ("x" + exporter.suffix)
        exporter.write(p, sample_inertial_estimates(), {"object_name": "t", "object_id": "t"})
        require(p.exists() and p.stat().st_size > 0, "write() produced no file")
        require("ICRF" in p.read_text(errors="replace"), "the written file does not name the frame (ICRF)")


def check_refuses_empty_estimates(exporter) -> None:
    e = sample_inertial_estimates()
    empty = InertialEstimates(e.frame, e.utc[:0], e.t_tu[:0], e.state_km[:0], e.covariance_km[:0], e.step[:0], e.kind[:0])
    with tempfile.TemporaryDirectory() as d:
        try:
            exporter.write(Path(d) / "x", empty, {})
        except CistrackError:
            return
    require(False, "writing an empty estimate did not raise a CistrackError")


EXPORTER_CHECKS = [
    ("is_exporter", check_is_exporter),
    ("writes_a_file_naming_the_frame", check_writes_a_file_naming_the_frame),
    ("refuses_empty_estimates", check_refuses_empty_estimates),
]
