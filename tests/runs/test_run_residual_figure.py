"""A filter run's residual figure: ``cistrack run SCENARIO --out DIR`` writes ``DIR/residuals.svg``,
one panel per site and measured component, with a point per update and the predicted 1-sigma and
3-sigma bands, drawn from the values ``DIR/steps.parquet`` holds. Real runs: the quick scenario
(one ground telescope, azimuth/elevation) and the shipped real-data scenario (two sites, RA/Dec)."""
from __future__ import annotations

import errno
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pyarrow.parquet as pq
import pytest

from cistrack.cli.main import main
from cistrack.results.store import read_manifest
from cistrack.runs.pipeline import run_scenario
from cistrack.runs.residual_figure import (FIGURE, residual_figure, residual_panels, write_residual_figure,
                                           write_run_residual_figure)
from cistrack.scenario.loading import load_scenario

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("quick") / "run"
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def real_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("real") / "run"
    return run_scenario(load_scenario("real-data"), output_dir=out, residual_figure=True), out


def _points(svg_path, gid: str) -> int:
    """Markers drawn in the SVG group ``gid`` (one ``<circle>`` per point)."""
    root = ET.parse(svg_path).getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == gid)
    return len(list(group.iter(f"{SVG}circle")))


def _drawn(svg: str, gid: str, attribute: str) -> np.ndarray:
    """The values the markers of group ``gid`` carry in ``attribute`` (data-days, data-value)."""
    group = next(g for g in ET.fromstring(svg).iter(f"{SVG}g") if g.get("id") == gid)
    return np.array([float(c.get(attribute)) for c in group.iter(f"{SVG}circle")])


def _updates(out, column: str) -> np.ndarray:
    values = pq.read_table(out / "steps.parquet").column(column).to_numpy(zero_copy_only=False)
    return np.asarray(values, dtype=float)[np.isfinite(np.asarray(values, dtype=float))]


def test_cistrack_run_writes_a_valid_svg_with_a_panel_per_component_and_a_point_per_update(quick_run):
    root = ET.parse(quick_run / FIGURE).getroot()
    assert root.tag == f"{SVG}svg"
    panels = [g.get("id") for g in root.iter(f"{SVG}g") if (g.get("id") or "").startswith("residuals-")]
    assert panels == ["residuals-sensor-azimuth", "residuals-sensor-elevation"]
    n = len(_updates(quick_run, "res_azimuth_arcsec"))
    assert n == 4  # the quick scenario's four updates after its IOD in 1.5 days
    assert _points(quick_run / FIGURE, "residuals-sensor-azimuth") == n
    assert _points(quick_run / FIGURE, "residuals-sensor-elevation") == n


def test_the_residuals_drawn_are_the_step_tables_values(quick_run):
    table = pq.read_table(quick_run / "steps.parquet")
    svg = residual_figure(residual_panels(table))
    for name in ("azimuth", "elevation"):
        res = np.asarray(table.column(f"res_{name}_arcsec").to_numpy(zero_copy_only=False), dtype=float)
        days = np.asarray(table.column("t_days").to_numpy(), dtype=float)
        assert np.array_equal(_drawn(svg, f"residuals-sensor-{name}", "data-value"), res[np.isfinite(res)])
        assert np.array_equal(_drawn(svg, f"residuals-sensor-{name}", "data-days"), days[np.isfinite(res)])


def test_the_bands_are_the_predicted_sigma_of_the_step_table(quick_run):
    table = pq.read_table(quick_run / "steps.parquet")
    for panel, name in zip(residual_panels(table), ("azimuth", "elevation")):
        assert np.array_equal(panel.sd, _updates(quick_run, f"sd_{name}_arcsec"))
    panels = ET.fromstring(residual_figure(residual_panels(table))).iter(f"{SVG}g")
    for panel, name in zip([g for g in panels if g.get("class") == "panel"], ("azimuth", "elevation")):
        bands = [g for g in panel.iter(f"{SVG}g") if (g.get("class") or "").startswith("band-")]
        assert [g.get("class") for g in bands] == ["band-3-sigma", "band-1-sigma"]
        for band in bands:
            drawn = np.array([float(v) for v in band.get("data-sd").split()])
            assert np.array_equal(drawn, _updates(quick_run, f"sd_{name}_arcsec"))
            assert band.findall(f"{SVG}path")  # a filled area per pass


def test_each_site_has_its_own_panels(real_run):
    res, out = real_run
    panels = residual_panels(pq.read_table(out / "steps.parquet"), res.context.measurements)
    assert [(p.site, p.name) for p in panels] == [("809", "right_ascension"), ("809", "declination"),
                                                  ("711", "right_ascension"), ("711", "declination")]
    ms = res.context.measurements
    index = _updates(out, "measurement_index")
    for p in panels:
        assert p.residual.size == sum(ms.site_at(int(i)) == p.site for i in index if i >= 0)
        assert _points(out / FIGURE, f"residuals-{p.site}-{p.name}") == p.residual.size


def test_a_table_without_residuals_leaves_no_figure_and_removes_an_earlier_one(quick_run, tmp_path):
    table = pq.read_table(quick_run / "steps.parquet")
    pq.write_table(table.drop([c for c in table.column_names if c.startswith(("res_", "sd_"))]),
                   tmp_path / "steps.parquet")
    (tmp_path / FIGURE).write_text("<svg/>")  # an earlier run's
    assert write_residual_figure(tmp_path) is None
    assert not (tmp_path / FIGURE).exists()


def test_a_full_disk_is_a_warning_and_the_run_stands(real_run, monkeypatch, caplog):
    res, out = real_run
    real_replace = os.replace

    def full(src, dst):
        if str(dst).endswith(FIGURE):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", full)
    before = (out / FIGURE).read_bytes()
    assert write_run_residual_figure(res.context, out, "finished") is None
    assert "residual figure was not written" in caplog.text and "No space left" in caplog.text
    assert (out / FIGURE).read_bytes() == before and read_manifest(out)["status"] == "finished"
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")]


def test_importing_the_pipeline_does_not_load_matplotlib():
    probe = ("import sys, cistrack.runs.pipeline, cistrack.runs.residual_figure\n"
             "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


def test_a_run_draws_no_figure_unless_asked(tmp_path):
    """Studies run many runs into folders: the figure is the CLI's and ``ct.run(out=...)``'s, not
    every run's."""
    run_scenario(load_scenario("quick").with_overrides({"duration_days": 1.5}), output_dir=tmp_path / "run")
    assert not (tmp_path / "run" / FIGURE).exists()


def test_the_results_line_names_the_residual_figure(quick_run):
    from cistrack.results.store import results_line

    assert results_line(quick_run).endswith(f", {quick_run}/manifest.json, {quick_run}/{FIGURE}")


def test_the_results_line_says_when_the_manifest_was_left_saying_running(tmp_path):
    import json

    from cistrack.results.store import results_line

    (tmp_path / "manifest.json").write_text(json.dumps({"status": "running"}))  # its final write failed
    assert results_line(tmp_path).endswith("manifest.json (still says 'running': its final version could not "
                                           "be written)")
    (tmp_path / "manifest.json").write_text(json.dumps({"status": "finished"}))
    assert results_line(tmp_path).endswith("manifest.json")
