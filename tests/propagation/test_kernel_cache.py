"""The kernel cache directory: private to its user, never shared, never silently replaced."""
from __future__ import annotations

import os
import stat
import subprocess
import sys

import pytest

from cistrack.errors import ConfigError
from cistrack.propagation import kernels


def test_cache_directory_is_created_private(tmp_path, monkeypatch):
    target = tmp_path / "cache" / "cistrack" / "kernels"
    monkeypatch.setenv("CISTRACK_KERNEL_DIR", str(target))
    assert kernels.secure_cache_dir() == target
    assert stat.S_IMODE(target.stat().st_mode) == 0o700


def test_a_relative_cache_directory_is_refused(monkeypatch):
    monkeypatch.setenv("CISTRACK_KERNEL_DIR", "kernels")  # would make a cache in every working directory
    with pytest.raises(ConfigError, match="CISTRACK_KERNEL_DIR='kernels': must be an absolute path"):
        kernels.kernel_cache_dir()


def test_cache_directory_writable_by_others_is_refused(tmp_path):
    target = tmp_path / "shared"
    target.mkdir()
    target.chmod(0o777)
    with pytest.raises(ConfigError, match=r"writable by group or others .*chmod 700") as exc:
        kernels.secure_cache_dir(target)
    assert str(target) in str(exc.value) and "CISTRACK_KERNEL_DIR" in str(exc.value)


def _foreign_directory(tmp_path):
    """A directory owned by another user: one we chown (as root), else the root directory."""
    if os.getuid() == 0:
        d = tmp_path / "foreign"
        d.mkdir(mode=0o700)
        os.chown(d, 65534, 65534)
        return d
    return type(tmp_path)("/")


def test_cache_directory_owned_by_another_user_is_refused(tmp_path):
    d = _foreign_directory(tmp_path)
    with pytest.raises(ConfigError, match="owned by another user"):
        kernels.secure_cache_dir(d)


def test_cache_directory_that_is_a_file_is_refused(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(ConfigError, match="not a directory"):
        kernels.secure_cache_dir(f)


def test_cli_run_with_a_foreign_kernel_directory_is_refused_before_computing(tmp_path):
    d = _foreign_directory(tmp_path)
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--out", str(tmp_path / "r"), "--quiet"],
                          capture_output=True, text=True, env={**os.environ, "CISTRACK_KERNEL_DIR": str(d)})
    assert proc.returncode == 2
    assert "owned by another user" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.slow
def test_unusable_cache_directory_compiles_in_memory_with_a_warning_and_no_shared_fallback(tmp_path):
    (tmp_path / "file").write_text("x")
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    code = ("import numpy as np\n"
            "from cistrack.plugins.dynamics.cr3bp import CR3BP\n"
            "p = CR3BP().propagate(np.array([[1.0221, 0, -0.1821, 0, -0.1033, 0]]), 0.0, 0.1)\n"
            "print(p.alive[0])\n")
    env = {**os.environ, "CISTRACK_KERNEL_DIR": str(tmp_path / "file" / "kernels"), "TMPDIR": str(tmpdir)}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "True"
    assert "compiling propagation kernels in memory" in proc.stderr
    assert list(tmpdir.iterdir()) == []


@pytest.mark.parametrize("value", ["abc", "0", "-2", "1.5", "100000"])
def test_invalid_thread_count_from_the_environment_is_refused(monkeypatch, value):
    monkeypatch.setenv("CISTRACK_NUM_THREADS", value)
    with pytest.raises(ConfigError, match="CISTRACK_NUM_THREADS.*integer from 1 to 1024"):
        kernels.num_threads()


def test_a_changed_kernel_helper_changes_the_kernel_digest(tmp_path):
    helper = tmp_path / "helper.py"
    helper.write_text("def view(a):\n    return a\n")
    before = kernels._helpers_digest((helper,))
    helper.write_text("def view(a):\n    return a[:]\n")
    assert kernels._helpers_digest((helper,)) != before
    assert any(path.name == "borrowed_view.py" and path.is_file() for path in kernels.HELPER_FILES)


def test_an_empty_home_gives_no_cache_directory_rather_than_one_at_the_root(monkeypatch):
    """Python takes the root directory for an empty HOME: the cache had been made at /.cache."""
    from cistrack.propagation.kernels import secure_cache_dir

    monkeypatch.delenv("CISTRACK_KERNEL_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", "")
    with pytest.raises(OSError, match="HOME is empty"):
        secure_cache_dir()


def test_a_home_that_does_not_exist_is_not_created_for_the_cache(monkeypatch, tmp_path):
    """HOME=/nonexistent had made /nonexistent/.cache/cistrack/kernels (as root, a top-level folder)."""
    from cistrack.propagation.kernels import secure_cache_dir

    monkeypatch.delenv("CISTRACK_KERNEL_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "nonexistent"))
    with pytest.raises(OSError, match="does not exist, and cistrack does not create one"):
        secure_cache_dir()
    assert not (tmp_path / "nonexistent").exists()


def test_plots_keep_matplotlib_out_of_a_home_that_does_not_exist(monkeypatch, tmp_path):
    """matplotlib had made $HOME/.config and $HOME/.cache, and for a HOME that is a file printed its
    own "mkdir -p failed" and MPLCONFIGDIR advice."""
    from cistrack.cli.plot_config import set_plot_config_dir

    monkeypatch.setenv("MPLCONFIGDIR", "")  # unset for the call; restored after the test
    monkeypatch.setenv("HOME", str(tmp_path / "nonexistent"))
    set_plot_config_dir()
    folder = os.environ["MPLCONFIGDIR"]
    assert os.path.isdir(folder) and not folder.startswith(str(tmp_path / "nonexistent"))


def test_an_unusable_cache_is_warned_about_once_per_cause():
    """Each kernel compiled had repeated the warning: a fit printed it twice."""
    import warnings

    kernels._WARNED.clear()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):
            kernels._warn_uncached(NotADirectoryError(20, "Not a directory", "/x/.cache"))
    assert len(caught) == 1 and "compiling propagation kernels in memory" in str(caught[0].message)
