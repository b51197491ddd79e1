"""argparse ``type=`` converters shared by the sub-commands: each refuses a bad value with a
message naming the option and what it takes (argparse prints it after the usage line)."""
from __future__ import annotations

import argparse
from typing import Callable

__all__ = ["path_text", "count", "port", "OnceOnly"]


def path_text(option: str) -> Callable[[str], str]:
    """A converter for a path option such as ``--out``: any non-blank text (an empty value would
    otherwise fall back silently to the default path)."""
    def convert(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"{text!r} is empty; give a path, or leave {option} out "
                                             "for the default")
        return text
    return convert


def count(minimum: int = 1) -> Callable[[str], int]:
    """A converter for a whole-number option of at least ``minimum``."""
    def convert(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number; give one >= {minimum}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{value}: give a whole number >= {minimum}")
        return value
    return convert



def port(default: int) -> Callable[[str], int]:
    """A converter for a TCP port option: decimal digits only, from 1 to 65535 (``default`` is
    named in the message)."""
    from cistrack.interfaces.limits import PORT_MAX, PORT_MIN

    def convert(text: str) -> int:
        if not (text.isascii() and text.isdigit()) or not PORT_MIN <= int(text) <= PORT_MAX:
            raise argparse.ArgumentTypeError(f"{text!r} is not a port: give an integer from {PORT_MIN} "
                                             f"to {PORT_MAX} (default {default})")
        return int(text)
    return convert


class OnceOnly(argparse.Action):
    """An option given at most once (argparse would keep the last of several silently): a second,
    different value is refused naming both, with what to do instead (``once_hint``)."""

    def __init__(self, *args, once_hint: str = "", **kwargs):
        self.once_hint = once_hint
        super().__init__(*args, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        seen = getattr(namespace, f"_{self.dest}_given", None)
        if seen is not None and seen != values:
            parser.error(f"{option_string} given twice ({seen} and {values}): it takes one value"
                         + (f"; {self.once_hint}" if self.once_hint else ""))
        setattr(namespace, f"_{self.dest}_given", values)
        setattr(namespace, self.dest, values)
