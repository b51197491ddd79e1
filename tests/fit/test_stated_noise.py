"""Stated uncertainties some N times too small (probe N1).

The shipped campaign's first three nights (35 observations of two sites, about 1" of noise) with
every rmsRA/rmsDec divided by 20: the fit's residuals are some 20 times the stated noise on every
night, at every site and in both angles. The fit had failed blaming burns of hundreds of m/s and
advised ``--set measurements.reader.sigma_arcsec=...``, which applies only to rows without their
own uncertainties and changed nothing. It now says first that the stated uncertainties look N
times too small; ``sigma_arcsec`` given for no row is warned of; and the ADES readers'
``sigma_from_file = false`` replaces a file's own uncertainties.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.runs.observation_files import read_observations
from cistrack.runs.run_inputs import weights_note
from cistrack.units import ARCSEC_RAD

SHIPPED = Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv"


def _tight_file(tmp_path: Path, divide: float = 20.0) -> Path:
    """The shipped file's rows before 2026-03-04, their rmsRA/rmsDec divided by ``divide``."""
    lines = [r for r in SHIPPED.read_text().splitlines() if r and not r.startswith("#")]
    out = [lines[0]]
    for row in lines[1:]:
        f = row.split("|")
        if f[3] < "2026-03-04":
            f[6], f[7] = repr(float(f[6]) / divide), repr(float(f[7]) / divide)
            out.append("|".join(f))
    path = tmp_path / "tight.psv"
    path.write_text("\n".join(out) + "\n")
    return path


def test_uncertainties_too_small_are_named_before_any_maneuver_words(tmp_path, capsys):
    rc = main(["fit", str(_tight_file(tmp_path)), "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    summary = out[out.index("fit cis0001:"):]
    said = summary.index("the stated uncertainties look ")
    factor = float(summary[said:].split()[4])
    assert 15.0 < factor < 30.0                                     # 20 times, as the residuals show it
    assert "maneuver" not in summary[:said] and "burn" not in summary[:said]
    assert "sigma_from_file=false" in summary
    rec = json.loads((tmp_path / "out" / "fit.json").read_text())
    if rc != 0:
        assert rec["failure"].startswith("the stated uncertainties look ")


def test_sigma_arcsec_that_applies_to_no_row_is_warned_of(tmp_path, capsys):
    path = _tight_file(tmp_path)
    main(["fit", str(path), "--out", str(tmp_path / "out"), "--set", "measurements.reader.sigma_arcsec=1.0",
          "--set", "iod.name=no-such-iod"])
    said = capsys.readouterr()
    assert "sigma_arcsec=1.0 applies to no observation" in said.out + said.err


def test_sigma_from_file_false_replaces_the_files_own_uncertainties(tmp_path):
    path = _tight_file(tmp_path)
    own = read_observations(path, epoch="2026-03-01T00:00:00Z", format="ades-psv")
    replaced = read_observations(path, epoch="2026-03-01T00:00:00Z", format="ades-psv", sigma_arcsec=0.8,
                                 sigma_from_file=False)
    assert np.all(own.sigmas[:, 1] < 0.1 * ARCSEC_RAD)
    assert replaced.sigmas[:, 1] == pytest.approx(np.full(len(replaced), 0.8 * ARCSEC_RAD))
    assert replaced.meta["default_sigma_count"] == len(replaced)
    assert "sigma_from_file = false: the file's own uncertainties are not used" in weights_note(replaced)


def test_uncertainties_far_too_large_are_warned_of(tmp_path, capsys):
    """Probe N: rmsRA = rmsDec 20 times the data's scatter had given chi-square 0.1 for 38 degrees
    of freedom and no word; the shipped file itself (its own uncertainties) gets none."""
    assert main(["fit", str(_tight_file(tmp_path, divide=1.0 / 20.0)), "--out", str(tmp_path / "wide")]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "the stated uncertainties look too large, and the covariance with them too wide" in out
    (tmp_path / "as").mkdir()
    assert main(["fit", str(_tight_file(tmp_path / "as", divide=1.0)), "--out", str(tmp_path / "as_stated")]) == 0
    assert "look too large" not in capsys.readouterr().out
