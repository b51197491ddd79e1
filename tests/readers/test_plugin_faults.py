"""A third party's reader or exporter that breaks its contract is named, never a traceback: one
that raises something other than cistrack's or the system's errors, calls sys.exit, returns what
is not a MeasurementSet, or (an exporter) writes nothing. Nothing is written then."""
from __future__ import annotations

import os

import pytest

from cistrack.errors import MeasurementError, PluginError
from cistrack.results.export_file import write_export
from cistrack.runs.observation_files import read_checked
from cistrack.testing.checks_reader import EPOCH, sample_measurements


class _Reader:
    """A third party's reader, doing ``mode``."""

    suffixes = (".evil",)

    def __init__(self, mode: str):
        self.mode = mode

    def read(self, path, epoch):
        if self.mode == "raise":
            raise RuntimeError("boom")
        if self.mode == "exit":
            raise SystemExit(3)
        if self.mode == "refuse":
            raise MeasurementError(f"{path}: line 1: not this format")
        return None if self.mode == "none" else sample_measurements("azel")


@pytest.mark.parametrize("mode, words", [("raise", "failed on obs.evil: RuntimeError: boom"),
                                         ("exit", "SystemExit: it called sys.exit(3)"),
                                         ("none", "returned NoneType for obs.evil, not a MeasurementSet")])
def test_a_reader_that_breaks_its_contract_is_named(mode, words):
    with pytest.raises(PluginError, match="reader '_Reader'") as exc:
        read_checked(_Reader(mode), "obs.evil", EPOCH)
    assert words in str(exc.value)


def test_a_readers_own_refusal_and_its_result_pass_through():
    with pytest.raises(MeasurementError, match="not this format"):
        read_checked(_Reader("refuse"), "obs.evil", EPOCH)
    assert len(read_checked(_Reader("ok"), "obs.evil", EPOCH)) == len(sample_measurements("azel"))


class _Exporter:
    def __init__(self, mode: str):
        self.mode = mode

    def write(self, path, estimates, meta):
        if self.mode == "raise":
            raise ValueError("boom")
        if self.mode == "exit":
            raise SystemExit(3)
        if self.mode == "ok":
            path.write_text("x\n")
        if self.mode == "dir":
            os.makedirs(path, exist_ok=True)
        if self.mode == "link":
            os.symlink("/etc/passwd", path)


@pytest.mark.parametrize("mode, words", [("raise", "failed: ValueError: boom"), ("exit", "sys.exit(3)"),
                                         ("nothing", "wrote nothing")])
def test_an_exporter_that_breaks_its_contract_is_named_and_leaves_no_file(tmp_path, mode, words):
    out = tmp_path / "q.evx"
    with pytest.raises(PluginError, match="exporter 'evx'") as exc:
        write_export(_Exporter(mode), out, None, {}, format="evx", named=True, overwrite=False)
    assert words in str(exc.value) and not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("mode", ["dir", "link"])
def test_an_exporter_that_makes_a_directory_or_link_at_its_path_is_named_not_the_out_path(tmp_path, mode):
    """It had been "--out q.evx: cannot write the evx file (File exists)" (probe I8)."""
    out = tmp_path / "q.evx"
    with pytest.raises(PluginError, match=r"^exporter 'evx' \(.*\) failed: FileExistsError: .*it must write a regular "
                                          r"file at the path it is given") as exc:
        write_export(_Exporter(mode), out, None, {}, format="evx", named=True, overwrite=False)
    assert "--out" not in str(exc.value) and list(tmp_path.iterdir()) == []


def test_an_exporter_that_writes_is_renamed_into_place(tmp_path):
    write_export(_Exporter("ok"), tmp_path / "q.evx", None, {}, format="evx", named=True, overwrite=False)
    assert (tmp_path / "q.evx").read_text() == "x\n"
