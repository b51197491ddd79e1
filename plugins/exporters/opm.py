"""CCSDS Orbit Parameter Message (OPM 2.0, KVN): exporter ``"opm"``.

The state vector and its covariance at one step (the last one by default; ``step`` selects
another), km and km/s, ``TIME_SYSTEM = UTC``, frame and ``meta["comments"]`` as in the OEM exporter;
``meta["data_comment"]`` replaces the comment that says what the state is (a filter's belief).
"""
from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from cistrack.interfaces.component import check_int
from cistrack.errors import CistrackError
from cistrack.api import hookimpl
from cistrack.interfaces import Exporter

from .ccsds_text import comment, kvn_text, COV_KEYS, ccsds_epoch, comment_lines, num

__all__ = ["OpmExporter", "read_opm"]

_STATE_KEYS = ("X", "Y", "Z", "X_DOT", "Y_DOT", "Z_DOT")


class OpmExporter(Exporter):
    """CCSDS OPM 2.0 (KVN): one state vector with its covariance.

    Parameters
    ----------
    step : int
        Step number to write; -1 (default) writes the last step.
    """

    suffix = ".opm"

    def __init__(self, step: int = -1) -> None:
        self.step = check_int(self, "step", step, minimum=-1)

    def write(self, path, estimates, meta: dict) -> None:
        est = estimates
        if len(est.utc) == 0:
            raise CistrackError(f"exporter 'opm': no estimates to write to {path}")
        if self.step == -1:
            k = len(est.utc) - 1
        else:
            hits = np.nonzero(np.asarray(est.step) == self.step)[0]
            if hits.size == 0:
                raise CistrackError(f"exporter 'opm': the run has no step {self.step} (steps "
                                    f"{int(est.step[0])}..{int(est.step[-1])})")
            k = int(hits[-1])
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")
        out = ["CCSDS_OPM_VERS = 2.0", *comment_lines(meta), f"CREATION_DATE = {now}",
               f"ORIGINATOR = {meta.get('originator', 'cistrack')}", ""]
        if not est.frame.ccsds:
            out += comment(f"REF_FRAME {est.frame.name}: {est.frame.description}")
        out += [f"OBJECT_NAME = {meta.get('object_name', 'cistrack-target')}",
                f"OBJECT_ID = {meta.get('object_id', 'cistrack-target')}",
                f"CENTER_NAME = {est.frame.center}", f"REF_FRAME = {est.frame.name}", "TIME_SYSTEM = UTC", "",
                *comment(meta.get("data_comment")
                         or f"moment-matched mean of the filter's belief at step {int(est.step[k])}, km and km/s"),
                f"EPOCH = {ccsds_epoch(est.utc[k])}"]
        out += [f"{key} = {num(v)}" for key, v in zip(_STATE_KEYS, est.state_km[k])]
        out.append("")
        c = est.covariance_km[k]
        pairs = [(i, j) for i in range(6) for j in range(i + 1)]
        out += [f"{key} = {num(c[i, j])}" for key, (i, j) in zip(COV_KEYS, pairs)]
        user = meta.get("user_defined") or {}
        if user:  # CCSDS OPM's user-defined parameters, e.g. a fitted area-to-mass ratio
            out += ["", *(f"USER_DEFINED_{k} = {num(v)}" for k, v in user.items())]
        Path(path).write_text(kvn_text("opm", out), encoding="utf-8")


def read_opm(path) -> dict:
    """Keyword values of an OPM written by :class:`OpmExporter`: 'EPOCH', 'REF_FRAME', 'state'
    (6,) km, km/s and 'covariance' (6, 6)."""
    kv = {}
    for line in Path(path).read_text().splitlines():
        if "=" in line and not line.startswith("COMMENT"):
            k, v = line.split("=", 1)
            kv[k.strip()] = v.strip()
    cov = np.zeros((6, 6))
    pairs = [(i, j) for i in range(6) for j in range(i + 1)]
    for key, (i, j) in zip(COV_KEYS, pairs):
        cov[i, j] = cov[j, i] = float(kv[key])
    return {"EPOCH": kv["EPOCH"], "REF_FRAME": kv["REF_FRAME"], "CENTER_NAME": kv["CENTER_NAME"],
            "state": np.array([float(kv[k]) for k in _STATE_KEYS]), "covariance": cov}


@hookimpl
def cistrack_register(registry):
    registry.add("exporter", "opm", OpmExporter)
