"""A truth burn that the scenario places after the run's end is not flown (probe N4).

``cistrack run`` said so in its log, but nothing under ``--quiet``, and a study of the scenario
ran it as a maneuver scenario ('1 runs completed', ``truth_maneuvers: []``) with no word. The run
now says it as a warning on stderr under ``--quiet`` too, and a study refuses such a scenario,
naming the study, the scenario file and the burn.
"""
from __future__ import annotations

from pathlib import Path

from cistrack.cli.main import main

QUICK = Path(__file__).parents[2] / "core/scenarios/quick.toml"
LATE_BURN = """
[truth.maneuvers]
name = "impulse"
t_days = 30.0
delta_v_ms = 1.0
direction = "in-track"
frame = "rtn-moon"
"""


def _scenario(tmp_path: Path) -> Path:
    path = tmp_path / "late_burn.toml"
    path.write_text(QUICK.read_text() + LATE_BURN)  # quick runs 3 days
    return path


def test_a_quiet_run_warns_of_a_burn_after_its_end(tmp_path, capsys):
    assert main(["run", str(_scenario(tmp_path)), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    said = capsys.readouterr()
    assert said.out == ""
    assert "warning:" in said.err and "[truth.maneuvers]: outside the run (0 to 3 days), not flown" in said.err
    assert "1 m/s in-track (rtn-moon) at 30 days" in said.err


def test_a_study_refuses_a_scenario_whose_burn_is_not_flown(tmp_path, capsys):
    scen = _scenario(tmp_path)
    study = tmp_path / "late.toml"
    study.write_text(f'name = "late"\nscenarios = ["{scen.name}"]\nseeds = [1]\n')
    assert main(["study", "run", str(study), "--out", str(tmp_path / "st"), "--workers", "1"]) != 0
    err = capsys.readouterr().err
    assert str(study) in err and str(scen.name) in err
    assert "1 m/s in-track (rtn-moon) at 30 days lies outside the run (0 to 3 days)" in err
    assert not (tmp_path / "st" / "runs").exists()
