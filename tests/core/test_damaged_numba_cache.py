"""A damaged entry of numba's on-disk cache (a truncated or garbled index or data file) is treated as
absent: the function is compiled again, a warning names the file, and the entry is rewritten. Numba
itself raised the unpickling error from every later run until someone deleted the file."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

MODULE = textwrap.dedent("""
    from cistrack.lazy import lazy_njit

    @lazy_njit(cache=True)
    def plus_one(x):
        return x + 1.0
""")

CALL = ("import logging, sys; logging.basicConfig(stream=sys.stderr, level=logging.WARNING); "
        "sys.path.insert(0, {where!r}); import cached_fn; print(cached_fn.plus_one(2.0))")


def _call(tmp_path):
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "nb"), "PATH": "/usr/bin:/bin"}
    return subprocess.run([sys.executable, "-c", CALL.format(where=str(tmp_path))], capture_output=True, text=True,
                          timeout=300, env=env)


@pytest.fixture
def damaged(tmp_path):
    (tmp_path / "cached_fn.py").write_text(MODULE)
    first = _call(tmp_path)
    assert first.stdout.split() == ["3.0"], first.stderr[-2000:]
    index = list((tmp_path / "nb").rglob("*.nbi"))
    assert index
    for f in index:
        f.write_bytes(b"garbage")
    return tmp_path


def test_a_damaged_index_is_compiled_again_with_a_warning_naming_it(damaged):
    proc = _call(damaged)
    assert proc.returncode == 0 and proc.stdout.split() == ["3.0"], proc.stderr[-2000:]
    assert "numba's cache file" in proc.stderr and ".nbi is damaged" in " ".join(proc.stderr.split())


def test_the_entry_is_rewritten_and_the_next_process_loads_it_silently(damaged):
    _call(damaged)
    proc = _call(damaged)
    assert proc.stdout.split() == ["3.0"] and "damaged" not in proc.stderr


def test_a_damaged_data_file_is_named_itself(tmp_path):
    (tmp_path / "cached_fn.py").write_text(MODULE)
    assert _call(tmp_path).stdout.split() == ["3.0"]
    for f in (tmp_path / "nb").rglob("*.nbc"):
        f.write_bytes(f.read_bytes()[:50])
    proc = _call(tmp_path)
    assert proc.stdout.split() == ["3.0"] and ".nbc is damaged" in " ".join(proc.stderr.split()), proc.stderr


def test_a_data_file_whose_unpickling_runs_out_of_memory_is_damage_too(tmp_path):
    """Garbled bytes can read as a length of exabytes: pickle raises MemoryError, not an unpickling error."""
    (tmp_path / "cached_fn.py").write_text(MODULE)
    assert _call(tmp_path).stdout.split() == ["3.0"]
    for f in (tmp_path / "nb").rglob("*.nbc"):
        f.write_bytes(b"\x80\x04\x8e" + (2 ** 62).to_bytes(8, "little"))
    proc = _call(tmp_path)
    assert proc.stdout.split() == ["3.0"] and "MemoryError" in proc.stderr and "Traceback" not in proc.stderr, proc.stderr


def test_a_data_file_that_leaves_a_buffer_exported_prints_no_bare_system_error(tmp_path):
    """A pickle's BYTEARRAY8 opcode with a length of exabytes: the unpickler's bytearray is freed
    while still exported, and CPython printed "SystemError: deallocated bytearray object has
    exported buffers" itself, a bare line before the warning that names the file."""
    (tmp_path / "cached_fn.py").write_text(MODULE)
    assert _call(tmp_path).stdout.split() == ["3.0"]
    for f in (tmp_path / "nb").rglob("*.nbc"):
        f.write_bytes(b"\x96" + (0x4D3A76D0BD77D5EB).to_bytes(8, "little"))
    proc = _call(tmp_path)
    assert proc.stdout.split() == ["3.0"] and ".nbc is damaged" in " ".join(proc.stderr.split()), proc.stderr
    assert "SystemError" not in proc.stderr, proc.stderr


def test_a_well_formed_pickle_of_something_else_is_compiled_again(tmp_path):
    """It unpickles, so the data file's loader passes it; numba's rebuild then raised a TypeError
    traceback (CompileResult._rebuild() missing 6 required positional arguments)."""
    import pickle

    (tmp_path / "cached_fn.py").write_text(MODULE)
    assert _call(tmp_path).stdout.split() == ["3.0"]
    for f in (tmp_path / "nb").rglob("*.nbc"):
        f.write_bytes(pickle.dumps(("x", 1, None)))
    proc = _call(tmp_path)
    assert proc.stdout.split() == ["3.0"] and "cannot be rebuilt" in proc.stderr and "Traceback" not in proc.stderr


TWO = MODULE + textwrap.dedent("""
    @lazy_njit(cache=True)
    def add(x, y, z):
        return x + y + z
""")


def _two_functions(tmp_path):
    """A module of two cached functions in ``tmp_path``, and a call of both in a fresh process."""
    (tmp_path / "cached_fn.py").write_text(TWO)
    call = CALL.replace("print(cached_fn.plus_one(2.0))", "print(cached_fn.plus_one(2.0), cached_fn.add(1.0, 2.0, 3.0))")
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "nb"), "PATH": "/usr/bin:/bin"}
    return lambda: subprocess.run([sys.executable, "-c", call.format(where=str(tmp_path))], capture_output=True,
                                  text=True, timeout=300, env=env)


def test_another_functions_entry_copied_over_is_compiled_again(tmp_path):
    """A mixed or stale cache: the run had called the other function's code ("dense_kernel expected
    13 arguments, got 3")."""
    run = _two_functions(tmp_path)
    assert run().stdout.split() == ["3.0", "6.0"]
    add = next((tmp_path / "nb").rglob("*add*.nbc"))
    for f in (tmp_path / "nb").rglob("*plus_one*.nbc"):
        f.write_bytes(add.read_bytes())
    proc = run()
    assert proc.stdout.split() == ["3.0", "6.0"], proc.stderr[-2000:]
    assert "holds another function's compiled code" in proc.stderr


def test_many_damaged_entries_are_one_warning(tmp_path):
    """A damaged cache had printed a warning per kernel (16-18 lines for one run); the first is
    said, with the others recompiled without a word."""
    run = _two_functions(tmp_path)
    assert run().stdout.split() == ["3.0", "6.0"]
    for f in (tmp_path / "nb").rglob("*.nbc"):
        f.write_bytes(b"garbage")
    proc = run()
    assert proc.stdout.split() == ["3.0", "6.0"] and proc.stderr.count("numba's cache") == 1, proc.stderr
