"""`cistrack plugins` refuses arguments it would otherwise ignore or blame on the plugin."""
from __future__ import annotations

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


def test_a_component_that_needs_a_parameter_is_told_the_command_lines_option(capsys):
    """The built-in rerun recorder needs somewhere to record: the advice is --param, not Python."""
    assert main(["plugins", "--check", "rerun"]) == 1
    out = capsys.readouterr().out
    assert 'cistrack plugins --check rerun --param path="out.rrd"' in " ".join(out.split())
    assert "check_plugin(" not in out and "check_registered(" not in out

