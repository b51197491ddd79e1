"""``cistrack export`` and ``ct.fit`` say on stderr what they are doing (they were silent for tens
of seconds), as ``cistrack run`` does; ``--quiet`` and ``progress=False`` silence them. Real runs
and fits: the quick scenario's run, the shipped real-data observations, a lone tracklet."""
from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq
import pytest

import cistrack as ct
from cistrack.cli.main import main

EXAMPLE = Path(__file__).resolve().parents[2] / "core/scenarios/real_data/observations.psv"
LONE = ("# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
        "halo|CCD|711|2026-08-08T10:10:54.459251Z|79.45130697317135|28.619129966967737|0.648|0.648|Gaia3\n"
        "halo|CCD|711|2026-08-08T10:14:32.774891Z|79.49241394217094|28.6267601916247|0.648|0.648|Gaia3\n"
        "halo|CCD|711|2026-08-08T10:18:01.093644Z|79.53137355766705|28.634043338470014|0.648|0.648|Gaia3\n")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "run"
    assert main(["run", "quick", "--set", "duration_days=1.5", "--out", str(out), "--quiet"]) == 0
    return out


def test_cistrack_export_shows_its_stages_on_stderr(run_dir, capsys):
    assert main(["export", str(run_dir)]) == 0
    err = capsys.readouterr().err.splitlines()
    n = pq.read_table(run_dir / "estimates.parquet").num_rows
    assert err == [f"cistrack: reading the estimates of {run_dir} and carrying them into the sensor's inertial frame",
                   f"cistrack: writing {n} estimates as oem to {run_dir / 'estimate.oem'}"]


def test_cistrack_export_of_a_step_the_run_lacks_refuses_it_without_saying_it_writes_it(run_dir, capsys):
    assert main(["export", str(run_dir), "--format", "opm", "--step", "99999", "--out", str(run_dir / "s.opm")]) == 2
    err = capsys.readouterr().err
    assert "no step 99999" in err and "writing" not in err
    assert not (run_dir / "s.opm").exists()


def test_cistrack_export_quiet_prints_nothing(run_dir, capsys):
    assert main(["export", str(run_dir), "--format", "opm", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    assert (run_dir / "estimate.opm").is_file()


def test_ct_fit_shows_each_stage_and_the_filter_on_stderr(tmp_path, capsys):
    [one] = ct.fit(EXAMPLE, out=tmp_path / "fit")
    err = capsys.readouterr().err
    n = len(one.run.context.measurements)
    assert f"{one.designation}: {n} observations; filter 'pgm'" in err
    assert f"least squares over the {n} observations" in err                    # after the filter, before the fit
    assert f"{one.designation}: writing fit.json, residuals.csv and the residual plots" in err
    assert "step/s" in err                                                        # the filter's progress bar


def test_ct_fit_of_a_lone_tracklet_says_so_on_stderr(tmp_path, capsys):
    (tmp_path / "lone.psv").write_text(LONE)
    [one] = ct.fit(tmp_path / "lone.psv", out=tmp_path / "out")
    err = capsys.readouterr().err
    assert "lone.psv: 3 observations" in err and one.failure in err


def test_ct_fit_without_progress_is_silent(tmp_path, capsys):
    (tmp_path / "lone.psv").write_text(LONE)
    ct.fit(tmp_path / "lone.psv", out=tmp_path / "out", progress=False)
    assert capsys.readouterr() == ("", "")
