"""An argument parser whose "invalid choice" error adds the closest choice ("did you mean 'fit'?"),
as the scenario, component and exporter names do."""
from __future__ import annotations

import argparse
import re
from typing import NoReturn

__all__ = ["SuggestingParser", "closest_choice"]

_INVALID = re.compile(r"invalid choice: '(?P<given>[^']*)' \(choose from (?P<choices>.*)\)$")


def closest_choice(given: str, choices: list[str]) -> str | None:
    """The one of ``choices`` that ``given`` most likely meant: the same name in another case, else
    the closest spelling (difflib, cutoff 0.5); None when none is close."""
    import difflib  # only a mistyped name needs it: not loaded on every start

    same = [c for c in choices if c.lower() == given.lower()]
    if same:
        return same[0]
    close = difflib.get_close_matches(given.lower(), choices, n=1, cutoff=0.5)
    return close[0] if close else None


class SuggestingParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` (sub-command parsers made from it are too) that ends an invalid
    choice's message with "did you mean 'X'?" when one choice is close."""

    def error(self, message: str) -> NoReturn:
        """Print the usage and ``message`` (with the suggestion) and exit with status 2."""
        m = _INVALID.search(message)
        if m:
            near = closest_choice(m["given"], re.findall(r"'([^']*)'", m["choices"]))
            message += f"; did you mean {near!r}?" if near else ""
        super().error(message)
