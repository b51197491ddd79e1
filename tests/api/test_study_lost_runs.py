"""``ct.study(...)`` never passes over runs that did not finish: some lost warns and lists them, all
lost raises, and a script without a ``__main__`` guard is told why its workers failed."""
from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import cistrack as ct
from cistrack.errors import CistrackError

SCENARIOS = Path(__file__).resolve().parents[2] / "core" / "scenarios"


def _study_with_a_missing_file(tmp_path: Path, scenarios: str) -> Path:
    bad = (SCENARIOS / "real-data.toml").read_text().replace('file = "real_data/observations.psv"',
                                                             'file = "missing.psv"')
    (tmp_path / "bad.toml").write_text(bad)
    study = tmp_path / "study.toml"
    study.write_text(f'name = "lossy"\nscenarios = {scenarios}\nfilters = [{{ name = "enkf" }}]\nseeds = [1]\n')
    return study


def test_a_study_with_a_run_that_did_not_finish_warns_and_lists_it(tmp_path):
    study = _study_with_a_missing_file(tmp_path, '["quick", "bad.toml"]')
    with pytest.warns(RuntimeWarning, match="1 of 2 runs did not finish.*missing.psv"):
        res = ct.study(study, out=tmp_path / "out", workers=1, settings={"duration_days": 2})
    assert [r.run_id for r in res.runs] == ["quick__enkf__noisy-range__seed1"]
    assert [rid for rid, _ in res.problems] == ["real-data__enkf__uniform-range__seed1"]


def test_a_study_none_of_whose_runs_finished_raises(tmp_path):
    study = _study_with_a_missing_file(tmp_path, '["bad.toml"]')
    with pytest.raises(CistrackError, match="none of its 1 runs finished.*missing.psv"):
        ct.study(study, out=tmp_path / "out", workers=1)


def test_a_script_that_runs_a_study_without_a_main_guard_is_told_to_add_one(tmp_path):
    script = tmp_path / "unguarded.py"
    script.write_text(textwrap.dedent(f"""
        import cistrack as ct
        ct.study("quick-comparison", n_seeds=1, out={str(tmp_path / "out")!r}, workers=1,
                 settings={{"duration_days": 2}})
        """))
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode != 0
    assert "none of its 2 runs finished" in done.stderr
    assert 'if __name__ == "__main__":' in done.stderr.splitlines()[-1]
