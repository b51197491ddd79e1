"""Every line ``cistrack`` prints for its listings and helps fits in 120 columns, whatever the
terminal's width (long descriptions wrap; a one-line-per-row table cuts them with '...')."""
from __future__ import annotations

import argparse

import pytest

from cistrack.cli.main import build_parser, main

MAX = 120


def _subcommands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """The argument paths of every subcommand of ``parser`` (``("study", "run")`` ...)."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out += [path + (name,)] + _subcommands(sub, path + (name,))
    return out


def _too_wide(text: str) -> list[str]:
    return [line for line in text.splitlines() if len(line) > MAX]


@pytest.fixture
def wide_terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", "300")  # what shutil.get_terminal_size reports to argparse


@pytest.mark.parametrize("argv", [["scenarios"], ["plugins"], ["plugins", "pgm"], ["plugins", "kmeans"]],
                         ids=" ".join)
def test_listings_fit_in_120_columns(argv, capsys, wide_terminal):
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.strip()
    assert _too_wide(out) == []


@pytest.mark.parametrize("argv", [()] + _subcommands(build_parser()), ids=lambda a: " ".join(a) or "cistrack")
def test_help_fits_in_120_columns_on_a_wide_terminal(argv, capsys, wide_terminal):
    with pytest.raises(SystemExit) as exit_:
        main([*argv, "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert "usage:" in out
    assert _too_wide(out) == []


def test_a_long_scenario_description_is_wrapped_not_lost(capsys):
    from cistrack.scenario.loading import builtin_scenarios

    main(["scenarios"])
    printed = " ".join(capsys.readouterr().out.split())
    for desc in builtin_scenarios().values():
        assert " ".join(desc.split()) in printed


def test_a_cut_plugin_summary_ends_with_an_ellipsis(capsys):
    from cistrack.plugin.registry import default_registry

    main(["plugins"])
    lines = capsys.readouterr().out.splitlines()
    for e in default_registry().entries("filter"):
        row = next(line for line in lines if line.split()[:1] == [e.name])
        shown = row.split(f" {e.version} ", 1)[1].strip()
        assert shown == e.summary or (shown.endswith("...") and e.summary.startswith(shown[:-3]))
