"""Third-party readers in `cistrack fit` (probe N13).

A reader plugin whose ``read`` builds a MeasurementSet with NaN values had failed the fit with
the set's own message, naming neither the reader, its distribution nor the file. A plugin reader
that claims ``.psv`` beside the built-in ``ades-psv`` had made every ``fit x.psv`` fail with
"give a file whose name ends in a known suffix". A real plugin distribution on PYTHONPATH, the
real CLI in a subprocess."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from plugin_site import plugin_site  # tests/ is on sys.path

READERS = '''
import numpy as np

from cistrack.api import MeasurementSet, hookimpl
from cistrack.interfaces.reader import Reader


class NanReader(Reader):
    """Claims .probe; builds a MeasurementSet of NaN angles."""

    suffixes = (".probe",)

    def read(self, path, epoch):
        return MeasurementSet(np.arange(5) * 0.01, np.full((5, 2), np.nan), np.full((5, 2), 1e-6),
                              ("right_ascension", "declination"))

    def write(self, path, measurements, epoch):
        raise NotImplementedError


class OtherPsv(Reader):
    """Claims .psv too."""

    suffixes = (".psv",)

    def read(self, path, epoch):
        raise NotImplementedError

    def write(self, path, measurements, epoch):
        raise NotImplementedError


@hookimpl
def cistrack_register(registry):
    registry.add("reader", "nan-read", NanReader)
    registry.add("reader", "other-psv", OtherPsv)
'''
SHIPPED = Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv"


def _cli(site: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    env.pop("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", None)
    return subprocess.run([sys.executable, "-m", "cistrack.cli", *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=600)


def _site(tmp_path: Path) -> Path:
    return plugin_site(tmp_path / "site", "cistrack-odd-readers", "0.3", {"cistrack_odd_readers": READERS})


def test_a_reader_plugins_own_error_names_the_reader_its_distribution_and_the_file(tmp_path):
    data = tmp_path / "a.probe"
    data.write_text("anything\n")
    done = _cli(_site(tmp_path), tmp_path, "fit", str(data), "--out", str(tmp_path / "out"))
    assert done.returncode != 0
    assert f"reader 'nan-read' (cistrack-odd-readers 0.3) failed on {data}" in done.stderr
    assert "NaN" in done.stderr


def test_a_suffix_two_readers_claim_names_both_and_the_setting_that_chooses(tmp_path):
    lines = [r for r in SHIPPED.read_text().splitlines() if r and not r.startswith("#")]
    data = tmp_path / "obs.psv"
    data.write_text("\n".join([lines[0], *[r for r in lines[1:] if r.split("|")[3] < "2026-03-03"]]) + "\n")
    site = _site(tmp_path)
    refused = _cli(site, tmp_path, "fit", str(data), "--out", str(tmp_path / "a"))
    assert refused.returncode != 0
    assert "reader 'ades-psv', reader 'other-psv' (cistrack-odd-readers 0.3)" in refused.stderr
    assert "--set measurements.reader.name=NAME" in refused.stderr and "known suffix" not in refused.stderr
    named = _cli(site, tmp_path, "fit", str(data), "--out", str(tmp_path / "b"), "--set",
                 "measurements.reader.name=ades-psv")
    assert "fit cis0001: converged" in named.stdout and "several readers" not in named.stderr  # its own copy too
