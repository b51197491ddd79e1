"""Keeping what the ``cistrack`` command prints within :data:`MAX_WIDTH` columns.

Listings wrap a long description under its own column (:func:`wrap_row`) or, in a table of one
line per row, cut it with ``...`` (:func:`fit_row`); help texts are wrapped by argparse at the
terminal's width, at most :data:`MAX_WIDTH` (:func:`cap_help_width`).
"""
from __future__ import annotations

import argparse
import re
import shutil
import textwrap

__all__ = ["MAX_WIDTH", "wrap_row", "fit_row", "wrap_lines", "wrap_labelled", "cap_help_width", "for_stream"]

#: the widest line the command prints, in characters
MAX_WIDTH = 120
_ELLIPSIS = "..."  # ASCII: a terminal that cannot show Unicode still shows it in three columns


def wrap_row(lead: str, text: str, width: int = MAX_WIDTH) -> list[str]:
    """``lead`` (a padded name column) then ``text`` wrapped to ``width`` columns, each further
    line indented to where ``text`` starts. A word longer than the line (a path) is never broken."""
    indent = " " * len(lead)
    lines = textwrap.wrap(text, width=width, initial_indent=lead, subsequent_indent=indent,
                          break_on_hyphens=False, break_long_words=False)
    return lines or [lead.rstrip()]


def fit_row(lead: str, text: str, width: int = MAX_WIDTH) -> str:
    """``lead + text`` on one line, ``text`` cut at a word and ended with ``...`` when the line
    would be wider than ``width`` columns."""
    line = lead + text
    if len(line) <= width:
        return line
    room = max(0, width - len(lead) - len(_ELLIPSIS))
    cut = text[:room]
    if text[room:room + 1] != " " and " " in cut:  # a word would be cut: end at the one before
        cut = cut.rsplit(" ", 1)[0]
    return lead + cut.rstrip(" ,;:.") + _ELLIPSIS


def wrap_lines(text: str, width: int = MAX_WIDTH) -> str:
    """``text`` with each line wider than ``width`` wrapped, its continuation lines indented like
    it (plus two spaces); a word longer than the line (a path) is never broken."""
    out: list[str] = []
    for line in text.splitlines():
        if len(line) <= width:
            out.append(line)
            continue
        indent = line[:len(line) - len(line.lstrip())]
        out += textwrap.wrap(line.strip(), width=width, initial_indent=indent, subsequent_indent=indent + "  ",
                             break_on_hyphens=False, break_long_words=False)
    return "\n".join(out)


_LABEL = re.compile(r"\s*[^:\s][^:]*?: ")
"""A line's label: leading spaces, then words up to the first ': ' (``  verdict: ``)."""
MAX_LABEL = 40
"""The longest label whose width continuation lines keep; a longer one is indented like the line."""


def wrap_labelled(line: str, width: int = MAX_WIDTH) -> list[str]:
    """``line`` within ``width`` columns: a line that starts with a short label (``  verdict: ``,
    ``cistrack: warning: ``...) continues under the text after its first label (:func:`wrap_row`),
    any other as :func:`wrap_lines` wraps it. Line breaks inside ``line`` are kept."""
    out: list[str] = []
    for part in line.split("\n"):
        label = _LABEL.match(part)
        if len(part) <= width:
            out.append(part)
        elif label and len(label.group(0)) <= MAX_LABEL:
            out += wrap_row(label.group(0), part[label.end():], width)
        else:
            out += wrap_lines(part, width).split("\n")
    return out


class _CappedHelpFormatter(argparse.HelpFormatter):
    """argparse's help layout at the terminal's width, never wider than :data:`MAX_WIDTH`."""

    def __init__(self, prog: str, *args, **kwargs):
        kwargs.setdefault("width", min(shutil.get_terminal_size().columns, MAX_WIDTH) - 2)
        super().__init__(prog, *args, **kwargs)


def cap_help_width(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """``parser`` and each of its subcommands' parsers (at any depth) print their help within
    :data:`MAX_WIDTH` columns; returns ``parser``."""
    parser.formatter_class = _CappedHelpFormatter
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in set(action.choices.values()):
                cap_help_width(sub)
    return parser


def for_stream(text: str, stream: object) -> str:
    """``text`` (an error or warning line) wrapped within 120 columns under its label when
    ``stream`` is a terminal (a person reads it); on one line otherwise (a log, a pipe, a script
    that greps it). A word longer than the line (a path) is never broken."""
    isatty = getattr(stream, "isatty", None)
    return "\n".join(wrap_labelled(text)) if callable(isatty) and isatty() else text
