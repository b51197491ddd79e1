from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest
from study_files import write_study



@pytest.fixture
def tiny_study(tmp_path) -> Path:
    return write_study(tmp_path)


@pytest.fixture(scope="module")
def obs_file(tmp_path_factory) -> Path:
    """Angles of the quick scenario (seed 1, 1.4 days) written as an observation CSV file (no truth)."""
    from cistrack.plugins.readers.csv_file import write_measurements
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    sim = run_scenario(load_scenario("quick").with_overrides({"duration_days": 1.4}), seed=1)
    obs = tmp_path_factory.mktemp("obs") / "obs.csv"
    write_measurements(obs, sim.context.measurements, "2026-01-01T00:00:00Z")
    return obs


@pytest.fixture
def observed_study(tmp_path, obs_file):
    """Run a small study of the quick scenario on ``obs_file``: call with (name, filter table as
    TOML, seeds as TOML); returns (study file, study directory)."""
    import concurrent.futures as cf

    from cistrack.studies.study import run_study

    def run(name: str, filter_table: str, seeds: str) -> tuple[Path, Path]:
        study = tmp_path / f"{name}.toml"
        study.write_text(f'name = "{name}"\nscenarios = ["quick"]\nseeds = {seeds}\n'
                         f'filters = [{filter_table}]\n'
                         f'iod = [{{ name = "noisy-range", n_particles = 300 }}]\n'
                         f'[overrides]\nduration_days = 1.4\nmeasurements = {{ file = "{obs_file}" }}\n')
        out = tmp_path / "s"
        run_study(study, out_dir=out, executor=cf.ThreadPoolExecutor(1), progress=False)
        return study, out

    return run


class SmallDisk:
    """A small tmpfs mounted at ``path``: :meth:`fill` leaves only so many bytes free (a real full
    disk: the kernel's own ENOSPC), :meth:`free_up` gives the space back."""

    def __init__(self, path: Path):
        self.path = path
        self.filler = path / ".filler"

    def fill(self, free_bytes: int) -> None:
        import os

        st = os.statvfs(self.path)
        avail = st.f_bavail * st.f_frsize
        with open(self.filler, "ab") as fh:
            fh.write(b"\0" * max(0, avail - free_bytes))

    def free_up(self) -> None:
        self.filler.unlink(missing_ok=True)

    def files(self) -> list[Path]:
        """Every file on the disk but the filler."""
        return sorted(p for p in self.path.rglob("*") if p.is_file() and p != self.filler)


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB tmpfs at ``tmp_path/disk`` (needs root and a kernel that lets us mount one)."""
    import os
    import shutil
    import subprocess

    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("needs root and mount(8) to make a small tmpfs")
    d = tmp_path / "disk"
    d.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m,mode=0755", "tmpfs", str(d)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    try:
        yield SmallDisk(d)
    finally:
        if subprocess.run(["umount", str(d)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(d)], capture_output=True)


@pytest.fixture
def open_tmp():
    """A fresh directory under /tmp that ``nobody`` can reach (pytest's own tmp_path lies in a
    root-only 0700 folder: ``nobody`` could not even look there)."""
    d = Path(tempfile.mkdtemp(prefix="cistrack-ro-"))
    d.chmod(0o755)
    yield d
    for p in d.rglob("*"):
        if p.is_dir() and not p.is_symlink():
            p.chmod(0o755)
    shutil.rmtree(d)


@pytest.fixture(scope="module")
def finished_quick_run(tmp_path_factory) -> Path:
    """A finished run of the quick scenario (1.4 days, 300 particles, seed 1), once per test module;
    tests copy it before editing it."""
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    small = {"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2}, "iod": {"n_particles": 300}}
    d = tmp_path_factory.mktemp("runs") / "finished"
    run_scenario(load_scenario("quick").with_overrides(small), seed=1, output_dir=d)
    return d
