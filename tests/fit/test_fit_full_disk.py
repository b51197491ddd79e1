"""`cistrack fit` on a disk that fills while it writes the fit's files: a clear error naming the file,
and nothing left that reads as a finished fit. The disk is full for the residual SVG only: its
writes go to /dev/full (every write there fails with ENOSPC, as on a full disk)."""
from __future__ import annotations

import builtins
import contextlib
import io
import os
import re
import shutil

import pytest

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"
FAST = ["--set", "iod.n_particles=1000", "--set", "filter.n_particles=1000"]
_FIT_SVG = re.compile(r"residuals-[^/]*\.svg")
"""The fit's residual plots (and their temporary files), not the filter run's residuals.svg."""


def _fit(out, full_disk_for_svg: bool) -> tuple[int, str]:
    """(exit status, stderr) of `cistrack fit` of the shipped ADES file into ``out``."""
    real_open = builtins.open

    def open_on_full_disk(file, mode="r", *args, **kwargs):
        if isinstance(file, (str, os.PathLike)) and "w" in mode and _FIT_SVG.search(os.fspath(file)):
            return real_open("/dev/full", mode, *args, **kwargs)
        return real_open(file, mode, *args, **kwargs)

    err = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        if full_disk_for_svg:
            mp.setattr(builtins, "open", open_on_full_disk)
        rc = main(["fit", str(DATA / "observations.psv"), "--out", str(out), *FAST, "--quiet"])
    return rc, err.getvalue()


@pytest.fixture(scope="module")
def failed_fit(tmp_path_factory):
    """(directory, exit status, stderr) of a fit whose residual SVG met a full disk."""
    out = tmp_path_factory.mktemp("fit") / "fit"
    rc, err = _fit(out, full_disk_for_svg=True)
    return out, rc, err


def test_a_full_disk_ends_the_fit_with_an_error_naming_the_file(failed_fit):
    out, rc, err = failed_fit
    assert rc == 2 and "Traceback" not in err
    (line,) = [x for x in err.splitlines() if x.startswith("cistrack: error:")]
    assert re.search(rf"{re.escape(str(out))}/residuals-\w+\.svg: cannot write the fit's results \(No space left on "
                     r"device\); no fit\.json was written", line), line


def test_a_full_disk_leaves_no_fit_file_and_no_partial_file(failed_fit):
    out, _, _ = failed_fit
    names = sorted(p.name for p in out.iterdir())
    assert "fit.json" not in names and "residuals.csv" not in names
    assert [n for n in names if n.startswith("residuals-") or n.endswith(".tmp")] == []


def test_the_directory_of_a_fit_that_could_not_write_its_files_is_not_exported(failed_fit, capsys):
    out, _, _ = failed_fit
    assert main(["export", str(out), "--out", str(out.parent / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert "fit did not complete (no fit.json)" in err and not (out.parent / "x.oem").exists()


def test_the_fit_runs_again_into_the_same_directory_once_there_is_room(failed_fit, tmp_path):
    out = tmp_path / "fit"
    shutil.copytree(failed_fit[0], out)
    rc, err = _fit(out, full_disk_for_svg=False)
    assert rc == 0, err
    assert (out / "fit.json").is_file() and list(out.glob("residuals-*.svg"))
    assert main(["export", str(out), "--quiet"]) == 0
