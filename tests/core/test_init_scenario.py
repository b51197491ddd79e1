"""``cistrack init [NAME]`` writes a commented scenario (the built-in example-1's values, every
component parameter explained) that ``cistrack run NAME.toml`` runs as written, and never
overwrites a file."""
from __future__ import annotations

import re
import subprocess
import sys

import pytest

from cistrack.cli.main import main
from cistrack.plugin.param_docs import param_docs
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import COMPONENT_TABLES, load_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@pytest.fixture
def written(tmp_path, capsys):
    assert main(["init", str(tmp_path / "my")]) == 0
    assert "cistrack run" in capsys.readouterr().out
    return tmp_path / "my.toml"


def test_init_writes_name_toml_named_for_its_stem(written):
    assert written.is_file()
    assert tomllib.loads(written.read_text())["name"] == "my"


def test_the_written_scenario_holds_example_1s_components_and_duration(written):
    mine, ex1 = load_scenario(written), load_scenario("example-1")
    assert mine.duration_days == ex1.duration_days and mine.predict_every_hours == ex1.predict_every_hours
    assert mine.truth_orbit == ex1.truth_orbit
    for table in COMPONENT_TABLES:
        assert mine.raw[table] == ex1.raw[table]


def test_every_table_and_parameter_is_explained_in_a_comment(written):
    text = written.read_text()
    reg = default_registry()
    for table, kind in COMPONENT_TABLES.items():
        assert f"\n[{table}]\n" in text and f"# [{table}]: the {kind}." in text
        factory = reg.get(kind, load_scenario(written).components[table].name).factory
        for p in param_docs(factory):
            if p.name != "epoch":
                assert re.search(rf"^# {p.name} \(", text, re.M), f"[{table}] {p.name} is not explained"
    for key in ("name", "epoch", "seed", "duration_days", "[truth]", "[run]", "[custody]", "[measurements]"):
        assert key in text


def test_uncommenting_every_default_gives_the_same_valid_scenario(written, tmp_path):
    lines = written.read_text().splitlines()
    out = []
    for line in lines:
        m = re.fullmatch(r"# ([a-z_]+ = .+)", line)
        if line == "# [custody]" or (m and "..." not in line and not line.startswith("# file =")):
            out.append(line[2:])
        else:
            out.append(line)
    full = tmp_path / "full.toml"
    full.write_text("\n".join(out) + "\n")
    a, b = load_scenario(full), load_scenario(written)
    assert a.custody == b.custody and a.truth_grid_minutes == b.truth_grid_minutes
    assert a.components["filter"].params["kept_spread"] == pytest.approx(0.7)


def test_init_refuses_to_overwrite_an_existing_file(tmp_path, capsys):
    mine = tmp_path / "mine.toml"
    mine.write_text("keep me\n")
    assert main(["init", str(mine)]) == 2
    assert "exists" in capsys.readouterr().err
    assert mine.read_text() == "keep me\n"


@pytest.mark.parametrize("name", [" ", "-x", ".x", "a\tb"])
def test_a_refused_name_is_told_the_rule_that_is_applied(tmp_path, capsys, monkeypatch, name):
    """The message states the rule init applies (it takes 'a b', so it must not say letters and digits only)."""
    monkeypatch.chdir(tmp_path)
    assert main(["init", "--", name]) == 2
    err = capsys.readouterr().err
    assert f"cistrack init NAME {name!r}" in err
    assert "not starting with '.', '-' or a space, nor ending with a space" in err
    assert "letters, digits" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name, example", [(".", "my-scenario"), ("runs/", "runs/my-scenario"), ("..", "../my-scenario")])
def test_a_folder_given_as_the_name_is_told_to_name_a_file_in_it(tmp_path, capsys, monkeypatch, name, example):
    """init . had quoted the empty name '' as 'empty or a relative directory' (probe H13)."""
    monkeypatch.chdir(tmp_path)
    assert main(["init", name]) == 2
    err = capsys.readouterr().err
    assert f"cistrack init NAME {name!r}: names a folder, not a scenario file; give a file name such as {example}" in err
    assert list(tmp_path.iterdir()) == []


def test_cistrack_run_runs_the_written_file_as_written(written, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", str(written), "--quiet",
                           "--out", str(tmp_path / "run")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "run" / "manifest.json").is_file()


def test_an_upper_case_toml_suffix_is_taken_as_the_suffix():
    """``init x.TOML`` had written x.TOML.toml, a scenario named "x.TOML"."""
    from cistrack.scenario.template import template_path

    assert str(template_path("sub/x.TOML")) == "sub/x.TOML"
