"""Hostile files and places for the command line: a broken estimates table, a read-only study
directory, a terminal that shows only ASCII, a run or an ``init`` on a full disk. Each ends in one
clear error line (or the right result), never a traceback, and leaves nothing that blocks a retry."""
from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.scenario.builtin_scenarios import builtin_scenario_path

SMALL = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
         "--set", "iod.n_particles=300"]


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory) -> Path:
    """The results directory of a finished small run of the quick scenario."""
    out = tmp_path_factory.mktemp("run") / "r"
    assert main(["run", "quick", "--out", str(out), "--quiet", *SMALL]) == 0
    return out


@pytest.fixture
def run_copy(finished_run, tmp_path) -> Path:
    out = tmp_path / "r"
    shutil.copytree(finished_run, out, symlinks=True)
    return out


def _export_error(run: Path, capsys) -> str:
    capsys.readouterr()
    assert main(["export", str(run), "--out", str(run.parent / "x.oem")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and not (run.parent / "x.oem").exists()
    return err


def test_export_of_an_empty_estimates_file_names_the_file(run_copy, capsys):
    (run_copy / "estimates.parquet").write_bytes(b"")
    err = _export_error(run_copy, capsys)
    assert f"cistrack: error: {run_copy / 'estimates.parquet'}: not a readable estimates table (0 bytes" in err


def test_export_through_a_symlink_to_a_file_that_is_not_parquet_names_the_link(run_copy, capsys):
    (run_copy / "estimates.parquet").unlink()
    (run_copy / "estimates.parquet").symlink_to(run_copy / "manifest.json")
    err = _export_error(run_copy, capsys)
    assert f"{run_copy / 'estimates.parquet'}: not a readable estimates table" in err


def test_export_through_a_symlink_to_another_table_says_it_is_not_an_estimates_table(run_copy, capsys):
    (run_copy / "estimates.parquet").unlink()
    (run_copy / "estimates.parquet").symlink_to("steps.parquet")
    err = _export_error(run_copy, capsys)
    assert f"{run_copy / 'estimates.parquet'}: not an estimates table (no column mean_km" in err


def test_export_through_a_dangling_symlink_says_where_it_points(run_copy, capsys):
    (run_copy / "estimates.parquet").unlink()
    (run_copy / "estimates.parquet").symlink_to(run_copy / "gone.parquet")
    err = _export_error(run_copy, capsys)
    assert f"{run_copy / 'estimates.parquet'}: a symbolic link to {run_copy / 'gone.parquet'}, which does not exist" in err


STUDY = """name = "tiny"
scenarios = ["quick"]
filters = [{ name = "pgm", n_particles = 300, n_components = 2 }]
iod = [{ name = "noisy-range", n_particles = 300 }]
seeds = [1]
[overrides]
duration_days = 1.4
"""


def test_study_report_on_a_read_only_study_directory_names_the_report_folder(tmp_path, capsys, monkeypatch):
    import concurrent.futures as cf

    from cistrack.studies.study import run_study

    study, out = tmp_path / "tiny.toml", tmp_path / "s"
    study.write_text(STUDY)
    run_study(study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False)
    real_mkdir = os.mkdir

    def read_only_mkdir(path, *args, **kwargs):  # the study directory lies on a read-only file system
        if Path(path).is_relative_to(out):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))
        return real_mkdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "mkdir", read_only_mkdir)
    capsys.readouterr()
    assert main(["study", "report", str(out)]) == 2
    err = capsys.readouterr().err
    assert (f"cistrack: error: study 'tiny': cannot write the report to {out / 'report'} (Read-only file system)"
            in err) and "Traceback" not in err


def test_a_unicode_scenario_name_prints_as_escapes_on_an_ascii_terminal(tmp_path):
    text = builtin_scenario_path("quick").read_text().replace('name = "quick"', 'name = "qu\u00efck-\u00df"', 1)
    scenario = tmp_path / "unicode.toml"
    scenario.write_text(text, encoding="utf-8")
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", str(scenario), "--out", str(tmp_path / "r"),
                           *SMALL], capture_output=True, cwd=tmp_path, timeout=600,
                          env=dict(os.environ, PYTHONIOENCODING="ascii"))
    out, err = proc.stdout.decode("ascii"), proc.stderr.decode("ascii")
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert "run qu\\xefck-\\xdf__" in out


def test_a_folder_left_by_a_run_that_failed_before_its_manifest_is_run_into(tmp_path, capsys):
    out = tmp_path / "r"
    for part_folder in ("steps", "estimates-parts"):  # what a run that met a full disk at its start leaves
        (out / part_folder).mkdir(parents=True)
    (out / ".run.lock").write_text("")
    assert main(["run", "quick", "--out", str(out), "--quiet", *SMALL]) == 0
    assert (out / "manifest.json").is_file() and (out / "steps.parquet").is_file()


def test_the_part_folders_a_failed_run_may_leave_are_the_folders_a_run_writes():
    from cistrack.results.earlier_run import RESULT_FOLDERS
    from cistrack.results.output_paths import PART_FOLDERS

    assert sorted(PART_FOLDERS) == sorted(RESULT_FOLDERS)


def test_a_part_folder_holding_other_files_still_makes_the_folder_refused(tmp_path, capsys):
    out = tmp_path / "r"
    (out / "steps").mkdir(parents=True)
    (out / "steps" / "notes.txt").write_text("mine")
    assert main(["run", "quick", "--out", str(out), "--quiet", *SMALL]) == 2
    assert f"--out {out}: is not empty and holds no cistrack manifest.json" in capsys.readouterr().err
    assert (out / "steps" / "notes.txt").read_text() == "mine"


def test_a_run_that_failed_on_a_full_disk_runs_again_once_there_is_room(small_disk, tmp_path):
    out = small_disk.path / "r"
    small_disk.fill(0)
    cmd = [sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), "--quiet", *SMALL]
    failed = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert failed.returncode != 0 and "No space left on device" in failed.stderr
    assert not (out / "manifest.json").exists()
    small_disk.free_up()
    retry = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert retry.returncode == 0, retry.stderr
    assert (out / "manifest.json").is_file() and (out / "steps.parquet").is_file()


def test_init_on_a_full_disk_leaves_no_file_and_the_next_init_writes_it(small_disk, monkeypatch, capsys):
    monkeypatch.chdir(small_disk.path)
    small_disk.fill(0)
    assert main(["init", "mine"]) == 2
    assert "mine.toml: cannot write it (No space left on device)" in capsys.readouterr().err
    assert small_disk.files() == []  # neither an empty mine.toml nor a temporary file
    small_disk.free_up()
    assert main(["init", "mine"]) == 0
    assert "[filter]" in (small_disk.path / "mine.toml").read_text()


def test_a_report_that_fails_half_way_leaves_the_earlier_report_whole(tmp_path, capsys, monkeypatch):
    """A full disk while the report is written: the earlier report stays as it was (it used to be
    mixed with the new one's first files), and no draft folder is left."""
    import concurrent.futures as cf

    from cistrack.studies.study import run_study

    study, out = tmp_path / "tiny.toml", tmp_path / "s"
    study.write_text(STUDY)
    run_study(study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False)
    assert main(["study", "report", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in (out / "report").iterdir()}
    real_replace = os.replace

    def disk_full_at_summary_md(src, dst, *args, **kwargs):
        if Path(dst).name == "summary.md":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", disk_full_at_summary_md)
    capsys.readouterr()
    assert main(["study", "report", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{out / 'report' / 'summary.md'}: No space left on device" in err and "left as it was" in err
    assert {p.name: p.read_bytes() for p in (out / "report").iterdir()} == before
    assert [p.name for p in out.iterdir() if p.name.startswith(".report")] == []
