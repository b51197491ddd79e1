"""A fit whose least squares runs off to an orbit far beyond cislunar space is not reported as
converged. The case: a fixed star (the same RA/Dec) observed from two sites on three nights, which
the least squares "fitted" 1.9e11 km away at 1.4e6 km/s (faster than light), exit status 0.
The whole fit of that file (about 30 s) is a slow case; the rule itself is tested directly."""
from __future__ import annotations

import io
import json
import sys
from dataclasses import replace

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.fitting.from_observations import CISLUNAR_LIMIT_KM

HEADER = ["# version=2022", "trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat"]


def _fit_at(state_lu_vu) -> object:
    """A converged least-squares result at ``state_lu_vu`` (6,), as a fit record holds it."""
    from cistrack.fitting.fit_export import _result

    return _result({"state": list(state_lu_vu), "covariance": (np.eye(6) * 1e-10).tolist(), "epoch_tu": 1.0,
                    "rms": 1.0, "chi2": 54.0, "n_used": 30, "n_rejected": 0, "iterations": 5, "converged": True,
                    "condition_number": 10.0, "weakest_direction_km": [0.0] * 6, "noise_scale": 1.0})


def test_the_rule_leaves_a_cislunar_fit_converged_and_fails_one_far_beyond():
    from types import SimpleNamespace

    from cistrack.fitting.from_observations import _refuse_not_cislunar

    near = SimpleNamespace(result=_fit_at([1.02, 0.0, -0.18, 0.0, -0.1, 0.0]))  # the 9:2 NRHO's apolune
    _refuse_not_cislunar(near)
    assert near.result.converged
    far = SimpleNamespace(result=_fit_at([500.0, 0.0, 0.0, 0.0, 3.0, 0.0]))       # 1.9e8 km
    _refuse_not_cislunar(far)
    assert not far.result.converged and far.result.messages[-1].startswith("not a cislunar orbit")


@pytest.fixture(scope="module")
def star_fit(tmp_path_factory):
    d = tmp_path_factory.mktemp("star")
    rows = [f"obj1|CCD|{site}|2026-03-0{2 + day}T{(hour * 60 + 20 * k) // 60:02d}:{(20 * k) % 60:02d}:00.000Z|"
            "123.456|12.345|1.0|1.0|Gaia3"
            for day in range(3) for site, hour in (("809", 2), ("711", 4)) for k in range(5)]
    (d / "star.psv").write_text("\n".join(HEADER + rows) + "\n")
    buf = io.StringIO()
    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "stdout", buf)
    try:
        rc = main(["fit", str(d / "star.psv"), "--out", str(d / "fit")])
    finally:
        mp.undo()
    return rc, buf.getvalue(), json.loads((d / "fit" / "fit.json").read_text()), d


@pytest.mark.slow
def test_a_fit_far_beyond_cislunar_space_is_not_converged_and_says_why(star_fit):
    rc, out, rec, _ = star_fit
    assert rc == 3 and rec["converged"] is False
    note = [m for m in rec["messages"] if m.startswith("not a cislunar orbit")]
    assert note and "do not determine the distance" in note[0]
    assert "not a cislunar orbit" in out and "next: cistrack export" not in out


@pytest.mark.slow
def test_its_state_is_indeed_beyond_the_limit(star_fit):
    rec = star_fit[2]
    assert np.linalg.norm(np.asarray(rec["state_km"])[:3]) > CISLUNAR_LIMIT_KM


@pytest.mark.slow
def test_such_a_fit_is_not_exported_and_the_refusal_gives_the_reason(star_fit, capsys):
    d = star_fit[3]
    assert main(["export", str(d / "fit"), "--out", str(d / "star.oem")]) == 2
    assert "not exported: the fit is not a cislunar orbit" in capsys.readouterr().err


def test_a_fit_whose_sigmas_reach_beyond_cislunar_space_is_not_converged_and_says_why():
    """Observations with legal but huge uncertainties (648000 arcsec) had "converged" to a fit whose
    1-sigma position, 3.5e6 km, export and predict then refused to read."""
    from types import SimpleNamespace

    from cistrack.fitting.from_observations import _refuse_unconfined

    state = [1.02, 0.0, -0.18, 0.0, -0.1, 0.0]
    wide = SimpleNamespace(result=replace(_fit_at(state), covariance=np.eye(6) * 1e2))  # sigma 10 LU, 3.8e6 km
    _refuse_unconfined(wide)
    assert not wide.result.converged
    assert wide.result.messages[-1].startswith("not a determined orbit: its 1-sigma position is 3.84e+06 km")


def test_a_fit_whose_sigmas_stay_within_cislunar_space_stays_converged():
    from types import SimpleNamespace

    from cistrack.fitting.from_observations import _refuse_unconfined

    near = SimpleNamespace(result=_fit_at([1.02, 0.0, -0.18, 0.0, -0.1, 0.0]))
    _refuse_unconfined(near)
    assert near.result.converged


def test_a_fit_not_reported_as_converged_says_why_in_its_failure_and_its_repr(tmp_path):
    """Probe L6: such a fit had ``failure`` "" (in the ObjectFit and fit.json) and the one-line reason
    "FAILED: converged after 5 iterations"; the reason it is not reported now fills both."""
    from cistrack.fitting.from_observations import ObjectFit, _name_failure, _refuse_unreportable
    from cistrack.scenario.loading import load_scenario

    far = _fit_at([500.0, 0.0, 0.0, 0.0, 3.0, 0.0])
    one = ObjectFit("far", tmp_path, load_scenario("real-data"), result=replace(far, messages=(
        "converged after 5 iterations",)))
    _refuse_unreportable(one)
    _name_failure(one)
    assert not one.ok and one.failure.startswith("not a cislunar orbit: the fitted state lies")
    assert repr(one).startswith("<ObjectFit far: FAILED: not a cislunar orbit") and "converged after" not in repr(one)


def test_a_least_squares_that_did_not_converge_says_so_in_its_failure(tmp_path):
    from cistrack.fitting.from_observations import ObjectFit, _name_failure
    from cistrack.scenario.loading import load_scenario

    r = replace(_fit_at([1.02, 0.0, -0.18, 0.0, -0.1, 0.0]), converged=False,
                messages=("no convergence within 30 iterations",))
    one = ObjectFit("slow", tmp_path, load_scenario("real-data"), result=r)
    _name_failure(one)
    assert one.failure == "the least squares did not converge (no convergence within 30 iterations)"


@pytest.mark.slow
def test_the_fit_json_of_such_a_fit_gives_the_reason_as_its_failure(star_fit):
    rec = star_fit[2]
    assert rec["failure"].startswith("not a cislunar orbit") and rec["failure"] in rec["messages"]
