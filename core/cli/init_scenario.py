"""The ``cistrack init [NAME]`` command: write a commented scenario file to start from
(:mod:`cistrack.scenario.template`)."""
from __future__ import annotations

from typing import Any

__all__ = ["add_init_parser", "cmd_init"]


def cmd_init(args: Any) -> int:
    """Write NAME.toml (never over an existing file) and say how to run it."""
    from cistrack.scenario.template import write_scenario_template

    import shlex

    path = write_scenario_template(args.name)
    print(f"wrote {path}: a commented scenario (the built-in example-1's values); run it with: cistrack run "
          f"{shlex.quote(str(path))}")
    return 0


def add_init_parser(subparsers: Any) -> None:
    """Add ``init`` to the ``cistrack`` command's subparsers."""
    p = subparsers.add_parser("init", help="write a commented scenario file to edit (NAME.toml; never overwrites)")
    p.add_argument("name", nargs="?", default=None, metavar="NAME",
                   help="the file to write, NAME.toml (default my-scenario.toml); its stem names the scenario")
    p.set_defaults(func=cmd_init)
