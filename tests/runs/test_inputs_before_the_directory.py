"""``cistrack run`` refuses an input that would only fail inside the run before it makes the results
directory: nothing is left behind."""
from __future__ import annotations

from cistrack.cli.main import main
from cistrack.scenario.loading import builtin_scenario_path


def test_a_missing_observation_file_is_refused_before_the_results_directory_is_made(tmp_path, capsys):
    text = builtin_scenario_path("real-data").read_text().replace('file = "real_data/observations.psv"',
                                                                 'file = "missing.psv"')
    (tmp_path / "bad.toml").write_text(text)
    assert main(["run", str(tmp_path / "bad.toml"), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert "[measurements] file = " in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_part_size_of_zero_is_refused_before_the_results_directory_is_made(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "out"), "--rows-per-part", "0", "--quiet"]) == 2
    assert "--rows-per-part" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_bad_background_compile_switch_is_refused_before_the_directory_even_with_kernels_cached(
        tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CISTRACK_BACKGROUND_COMPILE", "maybe")
    assert main(["run", "quick", "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert "CISTRACK_BACKGROUND_COMPILE='maybe'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_fit_and_study_run_check_the_environment_before_their_directories(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CISTRACK_BACKGROUND_COMPILE", "maybe")
    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    assert main(["fit", str(obs), "--out", str(tmp_path / "fit"), "--quiet"]) == 2
    assert main(["study", "run", "quick-comparison", "--out", str(tmp_path / "study"), "--quiet"]) == 2
    assert capsys.readouterr().err.count("CISTRACK_BACKGROUND_COMPILE='maybe'") == 2
    assert list(tmp_path.iterdir()) == []
