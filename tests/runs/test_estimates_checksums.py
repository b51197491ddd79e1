"""A run's Parquet tables carry a checksum on every page: a flipped bit in estimates.parquet had
been exported as other numbers in the OEM's last digits (11 of 64 single flips) or given a
ValueError traceback. Now any flip in a data page is refused naming the file."""
from __future__ import annotations

import shutil

import pytest

import cistrack as ct
from cistrack.cli.main import main


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    d = tmp_path_factory.mktemp("run") / "r"
    ct.run("quick", settings={"duration_days": 1.2}, out=d)
    return d


def _flipped(finished, tmp_path, offset: int):
    d = tmp_path / "r"
    shutil.copytree(finished, d)
    raw = bytearray((d / "estimates.parquet").read_bytes())
    raw[offset] ^= 0x10
    (d / "estimates.parquet").write_bytes(bytes(raw))
    return d


def test_every_flipped_bit_in_the_data_pages_is_refused_or_changes_nothing(finished, tmp_path, capsys):
    assert main(["export", str(finished), "--out", str(tmp_path / "clean.oem")]) == 0
    clean = (tmp_path / "clean.oem").read_text()
    size = (finished / "estimates.parquet").stat().st_size
    for k, offset in enumerate(range(4, size - 8, max(1, size // 40))):
        d = _flipped(finished, tmp_path / f"f{k}", offset)
        rc = main(["export", str(d), "--out", str(tmp_path / f"f{k}.oem")])
        err = capsys.readouterr().err
        assert "Traceback" not in err
        if rc == 0:
            assert (tmp_path / f"f{k}.oem").read_text().split("\n", 3)[3] == clean.split("\n", 3)[3], offset
        else:
            assert "estimates" in err, err
