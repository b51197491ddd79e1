"""What the command line says when a command is interrupted: each command's own words; an
interrupted ``study report`` had given ``study run``'s advice to run the rest (probe H8)."""
from __future__ import annotations

import argparse

from cistrack.cli.main import _interrupted_advice


def test_an_interrupted_study_report_says_no_report_was_written_not_study_runs_advice():
    said = _interrupted_advice(argparse.Namespace(cmd="study", study_cmd="report"))
    assert said == "; study report interrupted: no report was written (the runs are untouched)"


def test_an_interrupted_study_run_still_says_how_to_run_the_rest():
    assert "runs the rest" in _interrupted_advice(argparse.Namespace(cmd="study", study_cmd="run"))
