"""CCSDS Orbit Ephemeris Message (OEM 2.0, KVN): exporter ``"oem"``.

One segment: the run's estimate at every step (moment-matched mean of the filter's belief, in
km and km/s), with a covariance block (km^2, km^2/s, km^2/s^2; the lower triangle) at every
epoch. ``TIME_SYSTEM = UTC``; ``CENTER_NAME`` and ``REF_FRAME`` come from the run's inertial
frame; a frame that is not CCSDS-registered is named and described in a COMMENT line, and
``meta["comments"]`` (e.g. that the run did not finish) are COMMENT lines of the header; a comment
longer than a KVN line (254 characters) goes on over several, and a longer keyword line (an
OBJECT_NAME of more than 240 characters) is refused.
Numbers are written with the shortest text that reads back to the same double. Steps at the
same epoch (an update right after a prediction) keep the last one. ``meta["interpolation"]`` and
``meta["interpolation_degree"]`` (a fitted orbit on a regular grid) add the INTERPOLATION keywords,
and ``meta["data_comment"]`` replaces the comment that says what the states are.
"""
from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from cistrack.errors import CistrackError
from cistrack.api import hookimpl
from cistrack.interfaces import Exporter

from .ccsds_text import comment, kvn_text, ccsds_epoch, comment_lines, lower_triangle, num

__all__ = ["OemExporter"]


class OemExporter(Exporter):
    """CCSDS OEM 2.0 (KVN) with covariance: every step's mean state and covariance."""

    suffix = ".oem"

    def __init__(self) -> None:
        pass

    def write(self, path, estimates, meta: dict) -> None:
        est = estimates
        if len(est.utc) == 0:
            raise CistrackError(f"exporter 'oem': no estimates to write to {path}")
        keep = np.ones(len(est.utc), dtype=bool)
        keep[:-1] = np.diff(est.t_tu) > 0
        if np.any(np.diff(est.t_tu) < 0):
            raise CistrackError("exporter 'oem': estimate times are not in order")
        idx = np.nonzero(keep)[0]
        epochs = [ccsds_epoch(est.utc[k]) for k in idx]
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")
        out = ["CCSDS_OEM_VERS = 2.0", *comment_lines(meta), f"CREATION_DATE = {now}",
               f"ORIGINATOR = {meta.get('originator', 'cistrack')}", "", "META_START"]
        if not est.frame.ccsds:
            out += comment(f"REF_FRAME {est.frame.name}: {est.frame.description}")
        out += [f"OBJECT_NAME = {meta.get('object_name', 'cistrack-target')}",
                f"OBJECT_ID = {meta.get('object_id', 'cistrack-target')}",
                f"CENTER_NAME = {est.frame.center}", f"REF_FRAME = {est.frame.name}", "TIME_SYSTEM = UTC",
                f"START_TIME = {epochs[0]}", f"STOP_TIME = {epochs[-1]}"]
        if meta.get("interpolation"):  # states on a grid a reader may interpolate (a fitted orbit)
            out += [f"INTERPOLATION = {meta['interpolation']}",
                    f"INTERPOLATION_DEGREE = {int(meta.get('interpolation_degree', 7))}"]
        out += ["META_STOP", ""]
        out += comment(meta.get("data_comment") or "moment-matched mean of the filter's belief at each step, km and km/s")
        for e, k in zip(epochs, idx):
            out.append(" ".join([e] + [num(v) for v in est.state_km[k]]))
        out += ["", "COVARIANCE_START"]
        for e, k in zip(epochs, idx):
            out.append(f"EPOCH = {e}")
            out += [" ".join(num(v) for v in row) for row in lower_triangle(est.covariance_km[k])]
        out.append("COVARIANCE_STOP")
        Path(path).write_text(kvn_text("oem", out), encoding="utf-8")


@hookimpl
def cistrack_register(registry):
    registry.add("exporter", "oem", OemExporter)
