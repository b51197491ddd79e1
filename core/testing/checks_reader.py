"""Conformance checks for Reader plugins: write -> read round trips and refusals."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from cistrack.errors import MeasurementError
from cistrack.interfaces.reader import Reader
from cistrack.model.measurement import KIND_NAMES, MeasurementSet
from cistrack.astro.sites import observatory
from cistrack.units import ARCSEC_RAD, TU_S
from cistrack.testing.check_support import require

__all__ = ["READER_CHECKS", "sample_measurements"]

EPOCH = "2026-03-01T00:00:00Z"


def sample_measurements(kind: str, n: int = 12, seed: int = 5) -> MeasurementSet:
    """``n`` measurements of type ``kind`` from two MPC sites (705, 711), 40 min apart, with
    angles spread over the whole circle and 0.5-3 arcsec sigmas. Values in rad, times TU."""
    rng = np.random.default_rng(seed)
    times = (3600.0 + 2400.0 * np.arange(n) + rng.uniform(0, 1, n)) / TU_S
    a = rng.uniform(0.0, 2.0 * np.pi, n)
    b = rng.uniform(-1.2, 1.4, n) if kind == "radec" else rng.uniform(0.1, 1.5, n)
    sig = rng.uniform(0.5, 3.0, (n, 2)) * ARCSEC_RAD
    sites = np.where(np.arange(n) % 3 == 2, "711", "705")
    table = {c: observatory(c) for c in ("705", "711")}
    return MeasurementSet(times, np.column_stack([a, b]), sig, KIND_NAMES[kind], {}, sites,
                          np.full(n, kind), table)


def _round_trip(reader: Reader, kind: str) -> tuple[MeasurementSet, MeasurementSet]:
    ms = sample_measurements(kind)
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / ("obs" + (reader.suffixes[0] if reader.suffixes else ".txt"))
        reader.write(p, ms, EPOCH)
        back = reader.read(p, EPOCH)
    return ms, back


def check_is_reader(reader) -> None:
    require(isinstance(reader, Reader), f"{type(reader).__name__} does not derive from cistrack.interfaces.Reader")
    require(set(reader.measurement_kinds) <= set(KIND_NAMES) and reader.measurement_kinds,
            f"measurement_kinds {reader.measurement_kinds} must be a non-empty subset of {list(KIND_NAMES)}")


def check_round_trip(reader) -> None:
    """What the writer wrote reads back: same sites, types, values (to the stated resolution)."""
    for kind in reader.measurement_kinds:
        ms, back = _round_trip(reader, kind)
        require(len(back) == len(ms), f"{kind}: wrote {len(ms)} measurements, read {len(back)}")
        dt = np.abs(back.times - ms.times) * TU_S
        require(np.all(dt <= reader.time_resolution_s * 0.5 + 1e-9),
                f"{kind}: times differ by up to {dt.max():.3g} s (resolution {reader.time_resolution_s} s)")
        names = KIND_NAMES[kind]
        require(tuple(back.names[:2]) == names, f"{kind}: read names {back.names}, expected {names}")
        d = np.abs((back.values[:, :2] - ms.values[:, :2] + np.pi) % (2 * np.pi) - np.pi)
        tol = 0.5 * reader.angle_resolution_rad * 1.000001 + 1e-15
        require(np.all(d <= tol) if reader.angle_resolution_rad else np.array_equal(back.values, ms.values),
                f"{kind}: angles differ by up to {d.max():.3g} rad (resolution {reader.angle_resolution_rad})")
        if reader.carries_sigmas:
            require(np.array_equal(back.sigmas, ms.sigmas) if not reader.angle_resolution_rad
                    else np.allclose(back.sigmas, ms.sigmas, rtol=1e-3), f"{kind}: sigmas did not round-trip")
        require(back.sites is not None and back.sites.tolist() == ms.sites.tolist(), f"{kind}: sites did not round-trip")
        for key in ms.site_table:
            require(back.site_table.get(key) == ms.site_table[key], f"{kind}: site {key} did not round-trip")


def check_refuses_missing_file(reader) -> None:
    try:
        reader.read("/nonexistent/cistrack-check/obs" + (reader.suffixes[0] if reader.suffixes else ""), EPOCH)
    except MeasurementError as exc:
        require("nonexistent" in str(exc), f"the error for a missing file does not name it: {exc}")
        return
    require(False, "reading a missing file did not raise MeasurementError")


def check_refuses_garbage(reader) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / ("garbage" + (reader.suffixes[0] if reader.suffixes else ".txt"))
        p.write_text("this is not an observation file\n\x7f\x01 at all\n")
        try:
            reader.read(p, EPOCH)
        except MeasurementError as exc:
            require("line" in str(exc), f"the error for a malformed file does not name the line: {exc}")
            return
    require(False, "reading a malformed file did not raise MeasurementError")


READER_CHECKS = [
    ("is_reader", check_is_reader),
    ("round_trip", check_round_trip),
    ("refuses_missing_file", check_refuses_missing_file),
    ("refuses_garbage", check_refuses_garbage),
]
