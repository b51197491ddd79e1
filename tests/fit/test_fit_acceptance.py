"""`cistrack fit` with its defaults (4,000 particles) on the shipped example, exported as OEM, and
`ct.fit` on a file of two objects (slow: ~10 s of CPU per fit)."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
pytestmark = pytest.mark.slow


def _truth_in_oem_frame(fit_dir, epochs):
    """The shipped truth at the OEM's epochs (UTC text), in the OEM's frame (km, km/s)."""
    from cistrack import units
    from cistrack.fitting.fit_export import _scenario
    from cistrack.plugin.registry import default_registry

    reg = default_registry()
    scen = _scenario(fit_dir, reg)
    rows = [r for r in csv.reader(ln for ln in (DATA / "truth.csv").read_text().splitlines()
                                  if not ln.startswith("#"))][1:]
    t0 = (units.parse_utc(rows[0][0]) - scen.epoch).total_seconds() / units.TU_S
    x0 = units.state_from_km(np.array([float(v) for v in rows[0][1:]]))
    t = np.array([(units.parse_utc(e) - scen.epoch).total_seconds() / units.TU_S for e in epochs])
    states = scen.build("dynamics", reg).propagate(x0[None], t0, t).states[:, 0, :]
    return scen.build("sensor", reg).inertial_frame().from_synodic(states, t)


def test_defaults_put_the_truth_inside_the_exported_covariance_at_every_epoch_of_the_arc(tmp_path):
    oem = pytest.importorskip("oem")
    out = tmp_path / "fit"
    assert main(["fit", str(DATA / "observations.psv"), "--out", str(out), "--quiet"]) == 0
    assert main(["export", str(out), "--format", "oem"]) == 0
    seg = oem.OrbitEphemerisMessage.open(str(out / "estimate.oem")).segments[0]
    rows = list(seg.states)
    states = np.array([s.vector for s in rows])
    covs = np.array([c.matrix for c in seg.covariances])
    truth = _truth_in_oem_frame(out, [s.epoch.isot + "Z" for s in rows])
    m2 = [float((truth[k] - states[k]) @ np.linalg.solve(covs[k], truth[k] - states[k])) for k in range(len(rows))]
    assert max(m2) <= 16.8
    rec = json.loads((out / "fit.json").read_text())
    assert 0.8 <= rec["noise_scale"] <= 1.2


def test_a_file_of_two_objects_gives_two_fits_in_their_own_directories(tmp_path):
    import cistrack as ct

    lines = (DATA / "observations.psv").read_text().splitlines()
    header, rows = lines[:2], lines[2:]
    p = tmp_path / "two.psv"
    p.write_text("\n".join(header + rows + [r.replace("cis0001", "cis0002", 1) for r in rows]) + "\n")
    fits = ct.fit(p, out=tmp_path / "out", settings={"iod.n_particles": 1000, "filter.n_particles": 1000})
    assert [f.designation for f in fits] == ["cis0001", "cis0002"]
    assert [f.directory.name for f in fits] == ["fit-cis0001", "fit-cis0002"]
    assert all(f.ok for f in fits)
    assert json.loads((fits[1].directory / "fit.json").read_text())["designation"] == "cis0002"
