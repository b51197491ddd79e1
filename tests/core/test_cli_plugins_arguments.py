"""`cistrack plugins` refuses arguments it would otherwise ignore or blame on the plugin."""
from __future__ import annotations

import os

import pytest

from cistrack.cli.main import main


@pytest.mark.parametrize("argv, words", [
    (["plugins", "pgm", "--param", "n_particles=5"], "--param: sets a parameter for --check NAME only"),
    (["plugins", "--check", "kmeans", "--param", "zzz=1"], "'kmeans' takes no parameter 'zzz'; it takes"),
    (["plugins", "filter"], "cistrack plugins --kind filter"),
])
def test_an_argument_that_would_be_ignored_or_misread_is_refused_naming_it(argv, words, capsys):
    assert main(argv) == 2
    assert words in capsys.readouterr().err


def test_a_parameter_the_component_takes_is_checked_as_before(capsys):
    assert main(["plugins", "--check", "kmeans", "--param", "n_init=2"]) == 0
    assert capsys.readouterr().out.rstrip().endswith("0 failed")


def test_a_recorder_checked_without_parameters_records_to_a_temporary_file_it_then_removes(capsys):
    """The built-in rerun recorder needs somewhere to record; its own conformance check had failed."""
    assert main(["plugins", "--check", "rerun"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "checking recorder 'rerun' with path = '" in out and out.endswith("0 failed")
    path = out.split("with path = '")[1].split("'")[0]
    assert not os.path.exists(path) and not os.path.exists(os.path.dirname(path))


def test_a_component_that_cannot_be_built_is_told_the_command_lines_option(capsys):
    """Given parameters that leave the rerun recorder nothing to record to: the advice is --param, not Python."""
    assert main(["plugins", "--check", "rerun", "--param", "spawn=false"]) == 1
    out = capsys.readouterr().out
    assert 'cistrack plugins --check rerun --param path="out.rrd"' in " ".join(out.split())
    assert "check_plugin(" not in out and "check_registered(" not in out


def test_a_component_name_in_another_case_gets_did_you_mean(capsys):
    """`plugins PGM` had listed all 60 components, though `plugins pgn` got "did you mean 'pgm'?"."""
    assert main(["plugins", "PGM"]) == 2
    assert "no component named 'PGM'; did you mean 'pgm'?" in capsys.readouterr().err


def test_a_mistyped_subcommand_gets_did_you_mean(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["fitt", "x"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "invalid choice: 'fitt'" in err and err.rstrip().endswith("did you mean 'fit'?")
