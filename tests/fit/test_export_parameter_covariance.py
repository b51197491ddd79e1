"""The exported covariance of a fit that estimated the area-to-mass ratio carries the ratio's
uncertainty (issue 49, gap 4): :func:`cistrack.least_squares.area_to_mass.joint_covariances`
propagates the joint covariance of state and ratio (sigma points of both, each orbit integrated with
its own ratio; or the transition matrices with the trajectory's partial in the ratio), checked
against draws of both; and
``cistrack export`` of such a fit writes it.

Before, the export carried the state's covariance alone (the ratio's uncertainty was in it at the
fit epoch, as the Schur complement, but held fixed elsewhere): on the 10-day DRO arc below
(A/m 0.0105 +- 0.0058 m^2/kg, fit epoch at the arc's start) 150 states and ratios drawn from the
joint covariance had a mean Mahalanobis^2 of 12.5 under it 5 days on, 732 at 10 days, 13,446 at
20 days and 3,708 at 30 days (6 expected); under the joint covariance 5.5-5.9 (unscented) and
5.8-8.8 (linear).
"""
from __future__ import annotations

import importlib.util
import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from cistrack import units
from cistrack.cli.main import main
from cistrack.fitting.fit_export import export_fit
from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.least_squares.area_to_mass import joint_covariances
from cistrack.least_squares.prediction import predict_orbit
from cistrack.plugin.registry import default_registry
from cistrack.results.estimates import KM_SCALE
from cistrack.scenario.loading import builtin_scenario_path, parse_scenario

from .test_area_to_mass_recovery import OFFSET, simulate

AMR = "area_to_mass_m2_kg"
ROOT = Path(__file__).resolve().parents[2]
DAYS = np.array([5.0, 10.0, 20.0, 30.0])


@lru_cache(maxsize=1)
def _solved():
    """(fit dynamics, fit with the ratio estimated) of a 10-day DRO arc simulated with A/m 0.01."""
    dyn, sensor, ms, x0 = simulate(0.01, 10.0, seed=7)
    return dyn, fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass="solve"))


def _draws(dyn, res, times, n: int, seed: int) -> np.ndarray:
    """Offsets (n, K, 6) from the fitted orbit of orbits whose state and ratio are drawn from the
    joint covariance, each integrated with its own ratio."""
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(np.concatenate([res.state, res.parameters]), res.full_covariance, size=n)
    own = dyn.with_parameters(**{AMR: float(res.parameters[0])})
    centre = own.propagate(res.state[None], res.epoch, times).states[:, 0]
    out = [dyn.with_parameters(**{AMR: float(d[6])}).propagate(d[None, :6], res.epoch, times).states[:, 0] - centre
           for d in draws]
    return np.array(out)


def _mean_m2(offsets: np.ndarray, covs: np.ndarray) -> np.ndarray:
    return np.array([np.mean([e @ np.linalg.solve(covs[k], e) for e in offsets[:, k]]) for k in range(covs.shape[0])])


def test_at_the_fit_epoch_it_is_the_state_block():
    dyn, res = _solved()
    assert res.converged and res.full_covariance.shape == (7, 7)
    for how in ("unscented", "linear"):
        cov, linear = joint_covariances(dyn, res, np.array([res.epoch]), how)
        np.testing.assert_allclose(cov[0], res.covariance, rtol=1e-8, atol=0.0)


def test_a_fit_without_parameters_has_no_joint_covariance():
    dyn, res = _solved()
    from dataclasses import replace

    assert joint_covariances(dyn, replace(res, parameter_names=(), full_covariance=None), DAYS) is None


def test_the_joint_covariance_matches_draws_of_state_and_ratio():
    dyn, res = _solved()
    times = res.epoch + units.days_to_tu(DAYS)
    offsets = _draws(dyn, res, times, 150, seed=4911)
    joint, linear = joint_covariances(dyn, res, times)
    assert not np.any(linear)
    held = predict_orbit(res, dyn, times).covariances          # the ratio held at its estimate
    m2_joint, m2_held = _mean_m2(offsets, joint), _mean_m2(offsets, held)
    # chi-square, 6 degrees of freedom: mean 6, sd of a mean of 150 draws 0.28
    assert np.all((m2_joint > 4.8) & (m2_joint < 7.2)), m2_joint
    assert np.all(m2_held > 12.0) and m2_held.max() > 1000.0, m2_held
    sample = np.einsum("nki,nkj->kij", offsets, offsets) / offsets.shape[0]
    for k in range(len(times)):
        w, v = np.linalg.eigh(joint[k][:3, :3])
        drawn = float(v[:, -1] @ sample[k][:3, :3] @ v[:, -1])
        assert drawn == pytest.approx(w[-1], rel=0.25), (DAYS[k], drawn, w[-1])
    lin, _ = joint_covariances(dyn, res, times, "linear")
    sig = lambda c: np.sqrt(np.trace(c[:, :3, :3], axis1=1, axis2=2))  # noqa: E731
    np.testing.assert_allclose(sig(lin), sig(joint), rtol=0.05)


def _read_oem():
    spec = importlib.util.spec_from_file_location("check_fit", ROOT / "examples" / "real-data" / "check_fit.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.read_oem


@pytest.fixture(scope="module")
def fit_dir(tmp_path_factory):
    """A `cistrack fit` directory of the shipped example whose fit.json is given an estimated
    C_R A/m (0.01 +- 0.005 m^2/kg, correlated 0.5 with the state): what `auto` writes on a long arc."""
    d = tmp_path_factory.mktemp("amr") / "fit"
    data = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    rc = main(["fit", str(data), "--out", str(d), "--quiet", "--set", "iod.n_particles=1000",
               "--set", "filter.n_particles=1000"])
    assert rc == 0
    rec = json.loads((d / "fit.json").read_text())
    p = np.asarray(rec["covariance"])
    s = 0.005
    a = np.linalg.solve(p, np.ones(6))
    a *= 0.6 * s / np.sqrt(a @ p @ a)                         # a^T P a = (0.6 s)^2: correlation 0.51
    full = np.block([[p, (p @ a)[:, None]], [(a @ p)[None, :], np.array([[a @ p @ a + s * s]])]])
    rec["area_to_mass"] = {"estimated": True, "decision": "estimated (test)", "value_m2_kg": 0.01,
                           "sigma_m2_kg": float(np.sqrt(full[6, 6])), "sigma_scaled_m2_kg": float(np.sqrt(full[6, 6])),
                           "correlations_with_state": [0.5] * 6, "full_covariance": full.tolist(),
                           "parameter": "C_R A/m of the cannonball radiation pressure, m^2/kg"}
    (d / "fit.json").write_text(json.dumps(rec))
    return d, rec


def test_the_export_carries_the_ratio_uncertainty(fit_dir):
    d, rec = fit_dir
    out = export_fit(d, "oem", d / "joint.oem", predict_days=20.0)
    epochs, _states, covs = _read_oem()(out)
    text = out.read_text()
    assert "joint covariance of state and ratio" in text
    reg = default_registry()
    import tomllib

    scen = parse_scenario(tomllib.loads((d / "scenario.toml").read_text()), "scenario.toml", reg)
    dyn = scen.build("dynamics", reg).with_parameters(**{AMR: 0.01})
    from cistrack.fitting.fit_export import _result

    res = _result(rec)
    times = np.array([(units.parse_utc(e + ("" if e.endswith("Z") else "Z")) - scen.epoch).total_seconds()
                      for e in epochs]) / units.TU_S            # the OEM ends 1 ms before the lunar impact
    joint, _ = joint_covariances(dyn, res, times)
    held = predict_orbit(res, dyn, times).covariances
    km2 = KM_SCALE[0] ** 2
    tr = lambda c: np.trace(c[:, :3, :3], axis1=1, axis2=2)  # noqa: E731  (rotation invariant)
    np.testing.assert_allclose(tr(covs), tr(joint) * km2, rtol=1e-6)
    assert np.max(np.abs(tr(held) / tr(joint) - 1.0)) > 0.05       # the ratio's uncertainty shows
