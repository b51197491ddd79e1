"""A run's estimates on disk and exported as CCSDS OEM / OPM, checked with an independent reader
(the MIT-licensed `oem` package) and an independent frame check."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.results.estimates import KM_SCALE, read_estimates
from cistrack.runs.export import export_run, run_inertial_estimates
from cistrack.plugins.exporters.opm import read_opm
from cistrack.results.store import read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.units import LU_KM, TU_S


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    scen = load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2},
                                                  "iod": {"n_particles": 300}})
    res = run_scenario(scen, seed=3, output_dir=out, keep_steps=True)
    return out, res


def test_estimates_hold_every_step_mean_covariance_and_mixture(run_dir):
    out, res = run_dir
    est = read_estimates(out)
    assert len(est) == read_steps(out).num_rows
    last = res.steps[-1]
    mix = last.belief.mixture
    np.testing.assert_array_equal(est.mean_km[-1], mix.mean * KM_SCALE)
    np.testing.assert_array_equal(est.covariance_km[-1], mix.covariance * np.multiply.outer(KM_SCALE, KM_SCALE))
    np.testing.assert_array_equal(est.weights[-1], mix.weights)
    np.testing.assert_array_equal(est.means_km[-1], mix.means * KM_SCALE)
    assert est.covariances_km[-1].shape == (mix.n_components, 6, 6)


def test_the_mixture_moments_reproduce_the_stored_mean_and_covariance(run_dir):
    est = read_estimates(run_dir[0])
    for k in range(len(est)):
        w, m, c = est.weights[k], est.means_km[k], est.covariances_km[k]
        mean = w @ m
        d = m - mean
        cov = np.einsum("i,ijk->jk", w, c) + np.einsum("i,ij,ik->jk", w, d, d)
        np.testing.assert_allclose(mean, est.mean_km[k], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(cov, est.covariance_km[k], rtol=1e-7, atol=1e-12)


def test_oem_is_read_by_the_independent_oem_package_with_the_same_states_and_covariances(run_dir, tmp_path):
    oem = pytest.importorskip("oem")
    out, _ = run_dir
    path = export_run(out, "oem", tmp_path / "x.oem")
    ie, _ = run_inertial_estimates(out)
    msg = oem.OrbitEphemerisMessage.open(str(path))
    seg = msg.segments[0]
    assert seg.metadata["REF_FRAME"] == "CISTRACK-IDEAL-EQUATORIAL" and seg.metadata["TIME_SYSTEM"] == "UTC"
    rows = list(seg.states)
    states = np.array([s.vector for s in rows])
    keep = np.r_[np.diff(ie.t_tu) > 0, True]
    np.testing.assert_array_equal(states, ie.state_km[keep])
    covs = np.array([c.matrix for c in seg.covariances])
    np.testing.assert_array_equal(covs, ie.covariance_km[keep])
    t0 = rows[0].epoch
    dt = np.array([(s.epoch - t0).to_value("s") for s in rows])
    np.testing.assert_allclose(dt, (ie.t_tu[keep] - ie.t_tu[keep][0]) * TU_S, atol=2e-6)


def test_opm_carries_the_last_state_and_its_covariance(run_dir, tmp_path):
    out, _ = run_dir
    path = export_run(out, "opm", tmp_path / "x.opm")
    ie, _ = run_inertial_estimates(out)
    opm = read_opm(path)
    np.testing.assert_array_equal(opm["state"], ie.state_km[-1])
    np.testing.assert_array_equal(opm["covariance"], ie.covariance_km[-1])
    assert opm["REF_FRAME"] == "CISTRACK-IDEAL-EQUATORIAL" and opm["CENTER_NAME"] == "EARTH"


def test_inertial_velocity_is_the_time_derivative_of_inertial_position(run_dir):
    """Transport theorem checked by central differences along a synodic CR3BP trajectory."""
    from scipy.integrate import solve_ivp
    from reference_cr3bp import cr3bp_rhs
    _, res = run_dir
    frame = res.context.sensor.inertial_frame()
    x0 = res.context.truth_states[0]
    h = 1e-4
    ts = np.array([0.2 - h, 0.2, 0.2 + h])
    sol = solve_ivp(cr3bp_rhs, (0.0, 0.2 + h), x0, t_eval=ts, rtol=1e-12, atol=1e-13, method="DOP853")
    eci = frame.from_synodic(sol.y.T, ts)
    v_fd = (eci[2, :3] - eci[0, :3]) / (2 * h * TU_S)
    np.testing.assert_allclose(eci[1, 3:], v_fd, rtol=1e-6)
    rel = sol.y[:3, 1] - np.array([-1.2150582e-2, 0, 0])
    assert np.linalg.norm(eci[1, :3]) == pytest.approx(np.linalg.norm(rel) * LU_KM, rel=1e-13)


def test_covariance_maps_through_the_frame_jacobian_as_sampled_states_do(run_dir):
    """Monte Carlo: states drawn from the synodic estimate, mapped to the inertial frame, have
    the mapped covariance (the map is affine, so this holds to sampling error)."""
    out, res = run_dir
    est = read_estimates(out)
    ie, _ = run_inertial_estimates(out)
    k = len(est) - 1
    rng = np.random.default_rng(0)
    draws = rng.multivariate_normal(est.mean_km[k], est.covariance_km[k], size=20000) / KM_SCALE
    mapped = res.context.sensor.inertial_frame().from_synodic(draws, np.full(len(draws), est.t_tu[k]))
    emp = np.cov(mapped.T)
    sd = np.sqrt(np.diag(ie.covariance_km[k]))
    np.testing.assert_allclose(emp / np.outer(sd, sd), ie.covariance_km[k] / np.outer(sd, sd), atol=0.05)


def test_a_fit_stopped_before_its_filter_run_is_named_as_such(tmp_path):
    from cistrack.results.output_paths import FIT_STARTED

    (tmp_path / FIT_STARTED).write_text("")
    for call in (lambda: export_run(tmp_path), lambda: run_inertial_estimates(tmp_path)):
        with pytest.raises(ConfigError, match="a 'cistrack fit' began here and stopped before its filter run"):
            call()


def test_cli_export_writes_the_file_and_refuses_a_non_run(run_dir, tmp_path):
    out, _ = run_dir
    p = subprocess.run([sys.executable, "-m", "cistrack.cli", "export", str(out), "--format", "opm",
                        "--out", str(tmp_path / "c.opm")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "c.opm").exists()
    bad = subprocess.run([sys.executable, "-m", "cistrack.cli", "export", str(tmp_path)],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "not a cistrack run directory" in bad.stderr


def test_every_update_step_records_its_nis_and_the_run_passes_a_loose_nis_test(run_dir):
    from cistrack.evaluation.consistency import run_nis_test
    est = read_estimates(run_dir[0])
    upd = est.kind == "update"
    assert np.all(np.isfinite(est.nis[upd])) and np.all(est.nis_dof[upd] == 2)
    assert np.all(np.isnan(est.nis[~upd]))
    assert run_nis_test(run_dir[0]).n == int(upd.sum())


def test_an_existing_out_file_is_kept_unless_overwrite_is_given(run_dir, tmp_path, capsys):
    from cistrack.cli.main import main
    out, _ = run_dir
    target = tmp_path / "e.oem"
    target.write_text("an earlier export\n")
    assert main(["export", str(out), "--out", str(target)]) == 2
    assert "already exists" in capsys.readouterr().err and target.read_text() == "an earlier export\n"
    assert main(["export", str(out), "--out", str(target), "--overwrite"]) == 0
    assert target.read_text().startswith("CCSDS_OEM_VERS")


def test_an_out_file_in_the_folder_of_another_run_is_refused_naming_its_run_unless_overwrite(run_dir, tmp_path, capsys):
    """It had been written there beside that run's own results, to be taken for its export."""
    import json
    import shutil

    from cistrack.cli.main import main
    other = shutil.copytree(run_dir[0], tmp_path / "other")
    run_id = json.loads((other / "manifest.json").read_text())["run_id"]
    assert main(["export", str(run_dir[0]), "--out", str(other / "e.oem")]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert f"its folder {other} holds the results of the run {run_id!r} (manifest.json), not those of {run_dir[0]}" in err
    assert "add --overwrite" in err and not (other / "e.oem").exists()
    assert main(["export", str(run_dir[0]), "--out", str(other / "e.oem"), "--overwrite", "--quiet"]) == 0
    assert (other / "e.oem").read_text().startswith("CCSDS_OEM_VERS")


def test_a_default_export_that_holds_another_objects_export_is_refused_saying_so(run_dir, tmp_path, capsys):
    """Another run's export written there with --out DIR/estimate.oem --overwrite had been called an export of
    this run "made with other options"."""
    import re
    import shutil

    from cistrack.cli.main import main
    mine = shutil.copytree(run_dir[0], tmp_path / "mine", ignore=shutil.ignore_patterns("estimate.*"))
    assert main(["export", str(mine), "--quiet"]) == 0
    own = (mine / "estimate.oem").read_text()
    (mine / "estimate.oem").write_text(re.sub(r"OBJECT_ID = .*", "OBJECT_ID = someone-else", own))
    assert main(["export", str(mine), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "already holds an export of another object (OBJECT_ID = someone-else there, " in err
    assert "other options" not in err


@pytest.fixture
def run_copy(run_dir, tmp_path):
    import shutil
    d = tmp_path / "run"
    shutil.copytree(run_dir[0], d)
    return d


def _epoch(path) -> str:
    return read_opm(path)["EPOCH"]


def test_the_default_file_is_rewritten_with_the_same_export_but_not_replaced_by_another_step(run_copy, capsys):
    from cistrack.cli.main import main
    assert main(["export", str(run_copy), "--format", "opm", "--step", "5", "--quiet"]) == 0
    first = _epoch(run_copy / "estimate.opm")
    assert main(["export", str(run_copy), "--format", "opm", "--step", "5", "--quiet"]) == 0
    assert main(["export", str(run_copy), "--format", "opm", "--step", "3", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "estimate.opm: already holds a different export" in err and "--overwrite" in err
    assert _epoch(run_copy / "estimate.opm") == first


def test_the_log_of_an_opm_export_names_the_step_it_writes(run_copy, capsys):
    from cistrack.cli.main import main
    assert main(["export", str(run_copy), "--format", "opm", "--step", "3"]) == 0
    assert "writing step 3 as opm to" in capsys.readouterr().err


def test_an_export_into_a_missing_folder_is_refused_before_it_says_writing(run_copy, tmp_path, capsys):
    """Probe I8: it had printed "writing 12 estimates as oem to .../nope/x.oem" and then failed."""
    from cistrack.cli.main import main
    assert main(["export", str(run_copy), "--format", "oem", "--out", str(tmp_path / "nope" / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert "the folder" in err and "does not exist" in err and "writing" not in err


def test_export_run_from_python_names_its_keywords_when_the_path_exists(run_dir, tmp_path):
    out, _ = run_dir
    (tmp_path / "taken.oem").write_text("")
    with pytest.raises(ConfigError, match=r"path='.*taken.oem': already exists; give another file, or pass "
                                          r"overwrite=True"):
        export_run(out, "oem", tmp_path / "taken.oem")


def test_a_step_below_minus_one_is_refused_naming_step_and_what_it_takes(run_copy, capsys):
    """--step -5 had been refused as "exporter 'opm': parameter 'step' = -5 ... must be >= -1"."""
    from cistrack.cli.main import main
    assert main(["export", str(run_copy), "--format", "opm", "--step", "-5", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--step -5: give a step number of the run, 0 or more, or -1 for the last step" in err
    assert "parameter 'step'" not in err
