"""No result is lost: a failing observer, a full disk or a signal ends the run with the completed
steps merged and a manifest that says what happened; a study reruns what changed."""
from __future__ import annotations

import concurrent.futures as cf
import signal
import socket
import subprocess
import sys
import time

import pytest

from cistrack.errors import ConfigError
from cistrack.plugin.hookspecs import hookimpl
from cistrack.results.store import read_manifest, read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.studies.study import run_study


def _small():
    return load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2},
                                                  "iod": {"n_particles": 300}})


class FailsAtStep:
    """An observer (as a third-party recorder would be) that raises when step ``k`` is updated."""

    def __init__(self, k: int, exc: BaseException):
        self.k, self.exc = k, exc

    @hookimpl
    def cistrack_step_updated(self, run, step):
        if step.index >= self.k:
            raise self.exc


def test_a_failing_observer_ends_the_run_failed_with_completed_steps_merged(tmp_path):
    out = tmp_path / "r"
    res = run_scenario(_small(), seed=1, output_dir=out,
                       observers=[FailsAtStep(3, OSError(28, "No space left on device"))])
    assert res.summary.status == "failed"
    assert "No space left on device" in res.summary.failure
    man = read_manifest(out)
    assert man["status"] == "failed" and "No space left on device" in man["summary"]["failure"]
    steps = read_steps(out)
    assert (out / "steps.parquet").exists() and not list((out / "steps").glob("part-*"))
    assert steps.num_rows == len(res.rows) >= 3


def test_ctrl_c_ends_the_run_interrupted_with_completed_steps_merged(tmp_path):
    out = tmp_path / "r"
    with pytest.raises(KeyboardInterrupt):
        run_scenario(_small(), seed=1, output_dir=out, observers=[FailsAtStep(2, KeyboardInterrupt())])
    man = read_manifest(out)
    assert man["status"] == "interrupted"
    assert "SIGINT" in man["summary"]["failure"]
    assert (out / "steps.parquet").exists() and read_steps(out).num_rows >= 2


class InterruptedWhileFinishing:
    """An observer whose cistrack_run_finished is where a Ctrl-C arrives (a recorder flushing)."""

    @hookimpl
    def cistrack_run_finished(self, run, summary):
        raise KeyboardInterrupt()


def test_ctrl_c_while_an_observer_finishes_the_run_leaves_an_interrupted_manifest_with_steps_merged(tmp_path):
    out = tmp_path / "r"
    with pytest.raises(KeyboardInterrupt):
        run_scenario(_small(), seed=1, output_dir=out, observers=[InterruptedWhileFinishing()])
    man = read_manifest(out)
    assert man["status"] == "interrupted" == man["summary"]["status"]
    assert man["summary"]["failure"] == "interrupted (SIGINT, Ctrl-C) after the last step"
    assert (out / "steps.parquet").exists() and not list((out / "steps").glob("part-*"))


def test_sigterm_to_the_cli_leaves_an_interrupted_manifest_and_readable_steps(tmp_path):
    out = tmp_path / "term"
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(out), "--quiet",
                             "--rows-per-part", "1"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 240
    parts: list = []
    while time.time() < deadline:
        parts = list((out / "steps").glob("part-*.parquet")) if (out / "steps").exists() else []
        if len(parts) >= 2 or proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert len(parts) >= 2, "the run did not get two steps in"
    assert proc.returncode == 128 + signal.SIGTERM
    assert "interrupted (SIGTERM)" in err and "Traceback" not in err
    man = read_manifest(out)
    assert man["status"] == "interrupted" and "SIGTERM" in man["summary"]["failure"]
    assert read_steps(out).num_rows >= 2


def test_rerun_serve_with_the_port_taken_is_refused_before_computing(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        from cistrack.plugin.registry import default_registry
        from cistrack.errors import ParameterError
        with pytest.raises(ParameterError, match=f"127.0.0.1:{port} is already in use"):
            default_registry().create("recorder", "rerun", serve=True, serve_port=port)


def test_rerun_serve_from_the_cli_with_the_default_port_taken_fails_fast(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind(("127.0.0.1", 9876))
        except OSError:
            pytest.skip("port 9876 is held by another process")
        s.listen(1)
        t0 = time.time()
        proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(tmp_path / "r"),
                               "--rerun-serve", "--quiet"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "serve_port" in proc.stderr and "already in use" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "r" / "manifest.json").exists()  # nothing was computed
    assert time.time() - t0 < 60


def test_rerun_port_chooses_the_served_port_and_the_refusal_names_the_option(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(tmp_path / "r"),
                               "--rerun-serve", "--rerun-port", str(port), "--quiet"],
                              capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert f"127.0.0.1:{port} is already in use" in proc.stderr and "--rerun-port N" in proc.stderr


def test_rerun_port_without_rerun_serve_is_refused():
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--rerun-port", "9000"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "give --rerun-serve too" in proc.stderr


def test_rerun_to_an_unwritable_place_is_refused_before_computing(tmp_path):
    from cistrack.errors import ParameterError
    from cistrack.plugin.registry import default_registry

    with pytest.raises(ParameterError, match="cannot be written"):
        default_registry().create("recorder", "rerun", path=str(tmp_path / "no" / "such" / "dir" / "x.rrd"))


def test_default_results_directory_names_filter_and_iod(tmp_path):
    scen = tmp_path / "s.toml"
    scen.write_text((load_scenario("quick").source and open(load_scenario("quick").source).read())
                    .replace("n_particles = 1000", "n_particles = 300").replace("duration_days = 2.0", "duration_days = 1.4"))
    for f in ("pgm", "enkf"):
        proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", str(scen), "--quiet", "--set", f"filter.name=\"{f}\""]
                              + (["--set", "filter.n_components=2"] if f == "pgm" else []),
                              capture_output=True, text=True, cwd=tmp_path)
        assert proc.returncode in (0, 3), proc.stderr
    names = sorted(p.name.partition("__set-")[0] for p in (tmp_path / "runs").iterdir())  # --set: a suffix
    assert names == ["quick__enkf__noisy-range__seed1", "quick__pgm__noisy-range__seed1"]


STUDY = """
name = "fp"
scenarios = ["quick"]
filters = [{{ name = "pgm", n_particles = 200, n_components = 2 }}]
iod = [{{ name = "noisy-range", n_particles = 200 }}]
seeds = [1]
[overrides]
duration_days = {days}
"""


def test_a_study_whose_scenario_changed_reruns_a_finished_run_only_with_overwrite(tmp_path, capsys):
    p = tmp_path / "fp.toml"
    p.write_text(STUDY.format(days=1.4))
    out = tmp_path / "out"
    first = run_study(p, out_dir=out, workers=1, progress=False)
    assert (first["completed"], first["skipped"]) == (1, 0)
    again = run_study(p, out_dir=out, workers=1, progress=False)
    assert (again["completed"], again["skipped"]) == (0, 1)
    run_dir = next((out / "runs").iterdir())
    fp_before = read_manifest(run_dir)["fingerprint"]
    record = (out / "study.json").read_text()
    p.write_text(STUDY.format(days=1.3))
    with pytest.raises(ConfigError, match=rf"1 finished run\(s\) there were made with another scenario.*"
                                          rf"\({run_dir.name}\); add --overwrite"):
        run_study(p, out_dir=out, workers=1, progress=False)
    assert read_manifest(run_dir)["fingerprint"] == fp_before and (out / "study.json").read_text() == record
    changed = run_study(p, out_dir=out, workers=1, progress=False, overwrite=True)
    assert (changed["completed"], changed["skipped"]) == (1, 0)
    assert "fingerprint changed" in capsys.readouterr().err
    assert read_manifest(run_dir)["fingerprint"] != fp_before


def test_a_study_that_replaces_runs_removes_the_report_that_described_them(tmp_path, capsys):
    from cistrack.studies.report import report_study

    p = tmp_path / "fp.toml"
    p.write_text(STUDY.format(days=1.4))
    out = tmp_path / "out"
    run_study(p, out_dir=out, workers=1, progress=False)
    report_study(p, out_dir=out)
    assert (out / "report" / "runs.csv").is_file()
    p.write_text(STUDY.format(days=1.3))
    run_study(p, out_dir=out, workers=1, progress=False, overwrite=True)
    assert not (out / "report").exists()
    assert f"the report in {out / 'report'} described the runs replaced now and is removed" in " ".join(
        capsys.readouterr().err.split())


def test_a_study_resumes_an_interrupted_run(tmp_path):
    p = tmp_path / "fp.toml"
    p.write_text(STUDY.format(days=1.4))
    out = tmp_path / "out"
    run_study(p, out_dir=out, workers=1, progress=False)
    run_dir = next((out / "runs").iterdir())
    import json
    man = json.loads((run_dir / "manifest.json").read_text())
    man["status"] = "interrupted"
    (run_dir / "manifest.json").write_text(json.dumps(man))
    again = run_study(p, out_dir=out, workers=1, progress=False)
    assert (again["completed"], again["skipped"]) == (1, 0)
    assert read_manifest(run_dir)["status"] == "finished"


def test_a_study_run_that_adds_runs_removes_the_report_that_counted_fewer(tmp_path, capsys):
    import shutil

    from study_files import write_study

    from cistrack.studies.report import report_study

    p = write_study(tmp_path, seeds="[1, 2]")
    out = tmp_path / "out"
    run_study(p, out_dir=out, workers=1, progress=False)
    shutil.rmtree(next((out / "runs").iterdir()))  # as if the study had been interrupted before it
    report_study(p, out_dir=out)
    assert "1 of 2 runs complete" in (out / "report" / "summary.md").read_text()
    run_study(p, out_dir=out, workers=1, progress=False)  # resumed: runs the missing one
    assert not (out / "report").exists()
    assert f"the report in {out / 'report'} counted the runs done before this study run and is removed" in " ".join(
        capsys.readouterr().err.split())


class ReportsAfterTheFirstRun(cf.ThreadPoolExecutor):
    """A one-thread executor that takes 'cistrack study report' of the study as soon as its first run
    has ended, while the others still wait: the report of someone looking at a study still running."""

    def __init__(self, study, out):
        super().__init__(1)
        self.study, self.out, self.reports = study, out, []

    def submit(self, fn, /, *args, **kwargs):
        def then_report(*a, **k):
            summary = fn(*a, **k)
            if not self.reports:
                from cistrack.studies.report import report_study

                self.reports.append(report_study(self.study, out_dir=self.out))
                self.reports.append((self.out / "report" / "summary.md").read_text())
            return summary
        return super().submit(then_report, *args, **kwargs)


@pytest.fixture
def reported_while_running(tmp_path, capsys):
    """(the report taken after the study's first run, its summary.md then, the study directory, the
    study's stderr with its lines joined)."""
    from study_files import write_study

    p = write_study(tmp_path, seeds="[1, 2]")
    out = tmp_path / "out"
    ex = ReportsAfterTheFirstRun(p, out)
    run_study(p, out_dir=out, executor=ex, progress=False)
    ex.shutdown()
    return ex.reports[0], ex.reports[1], out, " ".join(capsys.readouterr().err.split())


def test_a_report_taken_while_a_study_run_runs_says_so_in_its_title(reported_while_running):
    """It had read like the final report of a study that was still running (probe I3)."""
    answer, summary_md, *_ = reported_while_running
    assert answer["study_running"]
    said = "1 of 2 runs complete, reported while a 'cistrack study run' (process "
    assert said in " ".join(answer["text"].split()) and said in summary_md
    assert "that study run removes this report when it ends" in summary_md


def test_a_study_run_removes_at_its_end_a_report_taken_while_it_ran(reported_while_running):
    """A report of 1 of 2 runs had been left in place after the study had run both (probe I3)."""
    *_, out, err = reported_while_running
    assert not (out / "report").exists()
    assert f"the report in {out / 'report'} was written while this study ran" in err
